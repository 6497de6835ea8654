// Typed parameters of one scene object as declared in the scene file, with query tracking so that
// parameters a plugin does not understand are reported as errors instead of silently ignored.
#pragma once
#include "core/transform.h"
#include "scene/object.h"

#include <map>
#include <memory>
#include <string>
#include <variant>
#include <vector>

namespace penumbra {

class Texture;

// An rgb/spectrum value (distinct from point/vector values, which share the Vec3f type).
struct ColorValue {
    Color3f rgb;
};

class Properties {
  public:
    // float, integer, boolean, string, rgb/spectrum (ColorValue), point/vector (Vec3f), transform, nested
    // object.
    using Value = std::variant<double, int64_t, bool, std::string, ColorValue, Vec3f, Transform,
                               std::shared_ptr<Object>>;
    enum class Tag { Float, Integer, Boolean, String, Color, Vector, Transform, Object };

    Properties() = default;
    Properties(std::string plugin, SourceLocation loc)
        : plugin_(std::move(plugin)), location_(std::move(loc)) {}

    const std::string& plugin() const { return plugin_; }
    const SourceLocation& location() const { return location_; }
    // Location of a named value, or of the object itself when unknown.
    const SourceLocation& location(const std::string& name) const;

    // ---- set (parser / loader). Setting an existing name is an error reported at `loc`.
    void set(const std::string& name, Value v, const SourceLocation& loc);
    // Nested objects without a `name` attribute get a unique generated name ("_arg_0", ...).
    void add_object(std::string name, std::shared_ptr<Object> obj, const SourceLocation& loc);

    bool has(const std::string& name) const { return values_.count(name) != 0; }
    // The type of a stored value, for parameters that accept several (e.g. an IOR: a float or a material
    // name). Does not mark the value as queried; a missing value is a LoadError.
    Tag type(const std::string& name) const;

    // ---- typed getters. Each marks the value as queried; a value of the wrong type is a LoadError.
    float get_float(const std::string& name) const;
    float get_float(const std::string& name, float def) const;
    int64_t get_int(const std::string& name) const;
    int64_t get_int(const std::string& name, int64_t def) const;
    bool get_bool(const std::string& name, bool def) const;
    std::string get_string(const std::string& name) const;
    std::string get_string(const std::string& name, const std::string& def) const;
    // Accepts rgb, spectrum (already converted to rgb) or a float (gray).
    Color3f get_color(const std::string& name) const;
    Color3f get_color(const std::string& name, const Color3f& def) const;
    // point and vector values.
    Vec3f get_vector(const std::string& name) const;
    Vec3f get_vector(const std::string& name, const Vec3f& def) const;
    Transform get_transform(const std::string& name, const Transform& def = Transform()) const;
    // A texture: a nested texture object, or a constant from rgb/spectrum/float.
    std::shared_ptr<Texture> get_texture(const std::string& name) const;
    std::shared_ptr<Texture> get_texture(const std::string& name, const Color3f& def) const;
    // A named nested object of the given kind (nullptr if absent).
    std::shared_ptr<Object> get_object(const std::string& name, ObjectKind kind) const;
    // All nested objects of a kind, in declaration order (marks them queried).
    std::vector<std::shared_ptr<Object>> objects(ObjectKind kind) const;
    // All nested objects in declaration order (not marked).
    const std::vector<std::pair<std::string, std::shared_ptr<Object>>>& all_objects() const {
        return objects_;
    }

    // Names set but never queried, in declaration order.
    std::vector<std::string> unqueried() const;
    // Throws a LoadError naming the first unqueried parameter.
    void check_all_queried(const std::string& what) const;
    // Throws "file:line: <what>: <message>" at the location of parameter `name`.
    [[noreturn]] void raise(const std::string& name, const std::string& message) const;

  private:
    struct Entry {
        Value value;
        SourceLocation loc;
        mutable bool queried = false;
        size_t order = 0;
    };
    const Entry* find(const std::string& name) const;
    [[noreturn]] void type_error(const std::string& name, const char* expected) const;

    std::string plugin_;
    SourceLocation location_;
    std::map<std::string, Entry> values_;
    std::vector<std::pair<std::string, std::shared_ptr<Object>>> objects_;
    size_t counter_ = 0;
};

} // namespace penumbra
