#include "scene/properties.h"

#include "scene/texture.h"

#include <algorithm>
#include <cmath>
#include <type_traits>

namespace penumbra {

namespace {
const char* tag_name(size_t index) {
    static const char* names[] = {"float", "integer",      "boolean",   "string",
                                  "rgb",   "point/vector", "transform", "object"};
    return index < 8 ? names[index] : "?";
}
} // namespace

const SourceLocation& Properties::location(const std::string& name) const {
    auto it = values_.find(name);
    return it == values_.end() ? location_ : it->second.loc;
}

void Properties::set(const std::string& name, Value v, const SourceLocation& loc) {
    if (values_.count(name))
        throw LoadError(loc, "parameter '" + name + "' of " + plugin_ + " is specified twice (first at " +
                                 values_.at(name).loc.str() + ")");
    if (const double* d = std::get_if<double>(&v); d && !std::isfinite(*d))
        throw LoadError(loc, "parameter '" + name + "' of " + plugin_ + " is not a finite number");
    if (const ColorValue* c = std::get_if<ColorValue>(&v); c && !is_finite(c->rgb))
        throw LoadError(loc, "parameter '" + name + "' of " + plugin_ + " has a non-finite component");
    if (const Vec3f* p = std::get_if<Vec3f>(&v); p && !is_finite(*p))
        throw LoadError(loc, "parameter '" + name + "' of " + plugin_ + " has a non-finite component");
    values_.emplace(name, Entry{std::move(v), loc, false, counter_++});
}

void Properties::add_object(std::string name, std::shared_ptr<Object> obj, const SourceLocation& loc) {
    if (name.empty()) name = "_arg_" + std::to_string(objects_.size());
    objects_.emplace_back(name, obj);
    set(name, Value(std::move(obj)), loc);
}

const Properties::Entry* Properties::find(const std::string& name) const {
    auto it = values_.find(name);
    if (it == values_.end()) return nullptr;
    it->second.queried = true;
    return &it->second;
}

void Properties::type_error(const std::string& name, const char* expected) const {
    const Entry* e = find(name);
    throw LoadError(e ? e->loc : location_, "parameter '" + name + "' of " + plugin_ + ": expected " +
                                                expected + ", got " + tag_name(e ? e->value.index() : 99));
}

void Properties::raise(const std::string& name, const std::string& message) const {
    throw LoadError(location(name), plugin_ + ": " + message);
}

static LoadError missing(const Properties& p, const std::string& name) {
    return LoadError(p.location(), p.plugin() + ": missing required parameter '" + name + "'");
}

// type() reads the Tag off the variant's index: both list the alternatives in the same order.
template <Properties::Tag tag, typename T>
constexpr bool tag_is = std::is_same_v<std::variant_alternative_t<size_t(tag), Properties::Value>, T>;
static_assert(std::variant_size_v<Properties::Value> == 8);
static_assert(tag_is<Properties::Tag::Float, double> && tag_is<Properties::Tag::Integer, int64_t> &&
              tag_is<Properties::Tag::Boolean, bool> && tag_is<Properties::Tag::String, std::string> &&
              tag_is<Properties::Tag::Color, ColorValue> && tag_is<Properties::Tag::Vector, Vec3f> &&
              tag_is<Properties::Tag::Transform, Transform> &&
              tag_is<Properties::Tag::Object, std::shared_ptr<Object>>);

Properties::Tag Properties::type(const std::string& name) const {
    const auto it = values_.find(name);
    if (it == values_.end()) throw missing(*this, name);
    return Tag(it->second.value.index());
}

float Properties::get_float(const std::string& name) const {
    const Entry* e = find(name);
    if (!e) throw missing(*this, name);
    if (auto d = std::get_if<double>(&e->value)) return float(*d);
    if (auto i = std::get_if<int64_t>(&e->value)) return float(*i);
    type_error(name, "float");
}
float Properties::get_float(const std::string& name, float def) const {
    return has(name) ? get_float(name) : def;
}

int64_t Properties::get_int(const std::string& name) const {
    const Entry* e = find(name);
    if (!e) throw missing(*this, name);
    if (auto i = std::get_if<int64_t>(&e->value)) return *i;
    type_error(name, "integer");
}
int64_t Properties::get_int(const std::string& name, int64_t def) const {
    return has(name) ? get_int(name) : def;
}

bool Properties::get_bool(const std::string& name, bool def) const {
    const Entry* e = find(name);
    if (!e) return def;
    if (auto b = std::get_if<bool>(&e->value)) return *b;
    type_error(name, "boolean");
}

std::string Properties::get_string(const std::string& name) const {
    const Entry* e = find(name);
    if (!e) throw missing(*this, name);
    if (auto s = std::get_if<std::string>(&e->value)) return *s;
    type_error(name, "string");
}
std::string Properties::get_string(const std::string& name, const std::string& def) const {
    return has(name) ? get_string(name) : def;
}

Color3f Properties::get_color(const std::string& name) const {
    const Entry* e = find(name);
    if (!e) throw missing(*this, name);
    if (auto c = std::get_if<ColorValue>(&e->value)) return c->rgb;
    if (auto d = std::get_if<double>(&e->value)) return Color3f(float(*d));
    if (auto i = std::get_if<int64_t>(&e->value)) return Color3f(float(*i));
    type_error(name, "rgb, spectrum or float");
}
Color3f Properties::get_color(const std::string& name, const Color3f& def) const {
    return has(name) ? get_color(name) : def;
}

Vec3f Properties::get_vector(const std::string& name) const {
    const Entry* e = find(name);
    if (!e) throw missing(*this, name);
    if (auto v = std::get_if<Vec3f>(&e->value)) return *v;
    type_error(name, "point or vector");
}
Vec3f Properties::get_vector(const std::string& name, const Vec3f& def) const {
    return has(name) ? get_vector(name) : def;
}

Transform Properties::get_transform(const std::string& name, const Transform& def) const {
    const Entry* e = find(name);
    if (!e) return def;
    if (auto t = std::get_if<Transform>(&e->value)) return *t;
    type_error(name, "transform");
}

std::shared_ptr<Texture> Properties::get_texture(const std::string& name) const {
    const Entry* e = find(name);
    if (!e) throw missing(*this, name);
    if (auto o = std::get_if<std::shared_ptr<Object>>(&e->value)) {
        if ((*o)->kind() != ObjectKind::Texture) type_error(name, "texture");
        return std::static_pointer_cast<Texture>(*o);
    }
    return make_constant_texture(get_color(name));
}
std::shared_ptr<Texture> Properties::get_texture(const std::string& name, const Color3f& def) const {
    return has(name) ? get_texture(name) : make_constant_texture(def);
}

std::shared_ptr<Object> Properties::get_object(const std::string& name, ObjectKind kind) const {
    const Entry* e = find(name);
    if (!e) return nullptr;
    auto o = std::get_if<std::shared_ptr<Object>>(&e->value);
    if (!o || (*o)->kind() != kind)
        throw LoadError(e->loc, "parameter '" + name + "' of " + plugin_ + ": expected a " + kind_name(kind));
    return *o;
}

std::vector<std::shared_ptr<Object>> Properties::objects(ObjectKind kind) const {
    std::vector<std::shared_ptr<Object>> result;
    for (const auto& [name, obj] : objects_)
        if (obj->kind() == kind) {
            values_.at(name).queried = true;
            result.push_back(obj);
        }
    return result;
}

std::vector<std::string> Properties::unqueried() const {
    std::vector<std::pair<size_t, std::string>> list;
    for (const auto& [name, e] : values_)
        if (!e.queried) list.emplace_back(e.order, name);
    std::sort(list.begin(), list.end());
    std::vector<std::string> names;
    for (auto& [order, name] : list)
        names.push_back(name);
    return names;
}

void Properties::check_all_queried(const std::string& what) const {
    for (const std::string& name : unqueried()) {
        const Entry& e = values_.at(name);
        if (auto o = std::get_if<std::shared_ptr<Object>>(&e.value))
            throw LoadError(e.loc,
                            what + " does not accept a nested " + kind_name((*o)->kind()) +
                                (name.rfind("_arg_", 0) == 0 ? std::string() : " named '" + name + "'"));
        throw LoadError(e.loc, "unknown parameter '" + name + "' of " + what);
    }
}

} // namespace penumbra
