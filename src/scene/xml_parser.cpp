// Mitsuba 3 XML -> XmlScene. Conventions follow Mitsuba 3's src/core/xml.cpp:
//  - `$name` in any attribute is replaced by a -D define or an earlier <default> (defines win, first default
//  wins);
//  - transform operations compose in document order, each new one applied after the previous: T = op * T;
//  - <spectrum> lists are converted to linear sRGB, bounded to [0,1] unless declared inside an <emitter> or
//  named
//    eta / k / int_ior / ext_ior; spectra outside an <emitter> are weighted by D65 (Mitsuba >= 3.6);
//  - <path> directories are relative to the file declaring them, <include> files resolve against the search
//  paths.
#include "scene/xml_parser.h"

#include "core/frame.h"
#include "core/spectrum.h"

#include <pugixml.hpp>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace penumbra {
namespace {

namespace fs = std::filesystem;
using Attributes = std::map<std::string, std::string>;

// One parsed text buffer: maps pugixml byte offsets to file:line.
struct Source {
    std::string file; // as shown in locations
    std::string dir;  // directory that relative <path> values start from
    std::vector<size_t> line_starts;

    Source(std::string file_, std::string dir_, const std::string& text)
        : file(std::move(file_)), dir(std::move(dir_)) {
        line_starts.push_back(0);
        for (size_t i = 0; i < text.size(); ++i)
            if (text[i] == '\n') line_starts.push_back(i + 1);
    }
    SourceLocation at(ptrdiff_t offset) const {
        const size_t off = offset < 0 ? 0 : size_t(offset);
        const auto it = std::upper_bound(line_starts.begin(), line_starts.end(), off);
        return {file, int(it - line_starts.begin())};
    }
    SourceLocation at(const pugi::xml_node& node) const { return at(node.offset_debug()); }
};

const std::map<std::string, ObjectKind>& object_tags() {
    static const std::map<std::string, ObjectKind> tags = {{"shape", ObjectKind::Shape},
                                                           {"bsdf", ObjectKind::BSDF},
                                                           {"texture", ObjectKind::Texture},
                                                           {"emitter", ObjectKind::Emitter},
                                                           {"sensor", ObjectKind::Sensor},
                                                           {"film", ObjectKind::Film},
                                                           {"rfilter", ObjectKind::RFilter},
                                                           {"sampler", ObjectKind::Sampler},
                                                           {"integrator", ObjectKind::Integrator},
                                                           {"medium", ObjectKind::Medium},
                                                           {"phase", ObjectKind::Phase},
                                                           {"volume", ObjectKind::Volume}};
    return tags;
}

bool is_value_tag(const std::string& tag) {
    return tag == "float" || tag == "integer" || tag == "boolean" || tag == "string" || tag == "rgb" ||
           tag == "spectrum" || tag == "point" || tag == "vector" || tag == "transform";
}
bool is_transform_op(const std::string& tag) {
    return tag == "translate" || tag == "rotate" || tag == "scale" || tag == "matrix" || tag == "lookat";
}
// Mitsuba's is_unbounded_spectrum(): index-of-refraction spectra are not clamped to [0,1].
bool is_unbounded_spectrum(const std::string& name) {
    return name == "eta" || name == "k" || name == "int_ior" || name == "ext_ior";
}

std::string read_text_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return {};
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

bool is_file(const std::string& p) {
    std::error_code ec;
    return fs::is_regular_file(p, ec);
}
bool is_directory(const std::string& p) {
    std::error_code ec;
    return fs::is_directory(p, ec);
}

// First existing `name` among `dirs` (or `name` itself when absolute); empty when not found.
std::string find_file(const std::string& name, const std::vector<std::string>& dirs) {
    if (fs::path(name).is_absolute()) return is_file(name) ? name : std::string();
    for (const auto& d : dirs) {
        const std::string candidate = (fs::path(d) / name).lexically_normal().string();
        if (is_file(candidate)) return candidate;
    }
    return {};
}

// Numbers, colors and vectors are separated by whitespace and/or commas.
std::vector<std::string> tokenize(const std::string& s, const char* delims = " \t\r\n,") {
    std::vector<std::string> out;
    size_t i = 0;
    while (i < s.size()) {
        const size_t start = s.find_first_not_of(delims, i);
        if (start == std::string::npos) break;
        const size_t end = s.find_first_of(delims, start);
        out.push_back(s.substr(start, end == std::string::npos ? std::string::npos : end - start));
        i = end == std::string::npos ? s.size() : end;
    }
    return out;
}

bool only_space_from(const char* p) {
    while (*p != '\0' && std::isspace(static_cast<unsigned char>(*p)))
        ++p;
    return *p == '\0';
}

// Parses the whole of `text` as a number; `what` names the attribute for the error message.
double parse_float(const std::string& text, const SourceLocation& loc, const std::string& what) {
    const char* begin = text.c_str();
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(begin, &end);
    if (end == begin || !only_space_from(end) || errno == ERANGE)
        throw LoadError(loc, what + ": expected a floating-point number, got '" + text + "'");
    return v;
}

int64_t parse_integer(const std::string& text, const SourceLocation& loc, const std::string& what) {
    const char* begin = text.c_str();
    char* end = nullptr;
    errno = 0;
    const long long v = std::strtoll(begin, &end, 10);
    if (end == begin || !only_space_from(end) || errno == ERANGE)
        throw LoadError(loc, what + ": expected an integer, got '" + text + "'");
    return int64_t(v);
}

Vec3f parse_vec3(const std::string& text, const SourceLocation& loc, const std::string& what,
                 bool allow_scalar) {
    const auto tokens = tokenize(text);
    if (tokens.size() == 1 && allow_scalar) return Vec3f(float(parse_float(tokens[0], loc, what)));
    if (tokens.size() != 3)
        throw LoadError(loc, what + ": expected " + std::string(allow_scalar ? "1 or 3" : "3") +
                                 " numbers, got '" + text + "'");
    return {float(parse_float(tokens[0], loc, what)), float(parse_float(tokens[1], loc, what)),
            float(parse_float(tokens[2], loc, what))};
}

// "major.minor.patch"; scenes older than 2.0.0 use Mitsuba 0.6 names (camelCase, lookAt) and are rejected.
void check_version(const std::string& version, const SourceLocation& loc) {
    const auto parts = tokenize(version, ".");
    if (parts.size() != 3 || !std::all_of(parts.begin(), parts.end(), [](const std::string& p) {
            return std::all_of(p.begin(), p.end(),
                               [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
        }))
        throw LoadError(loc, "could not parse scene version '" + version +
                                 "' (expected major.minor.patch, e.g. 3.0.0)");
    if (std::strtol(parts[0].c_str(), nullptr, 10) < 2) // saturates (no exception) for huge numbers
        throw LoadError(
            loc, "scene version " + version +
                     " is a Mitsuba 0.6 scene; penumbra reads Mitsuba 3 scenes (version 2.0.0 or later)");
}

class Parser {
  public:
    Parser(const std::map<std::string, std::string>& defines, std::string first_dir) : params_(defines) {
        scene_.search_paths.push_back(std::move(first_dir));
    }

    XmlScene parse_root(const std::string& text, const std::string& file, const std::string& key) {
        include_stack_.push_back(key);
        pugi::xml_document doc;
        const Source src(file, scene_.search_paths.front(), text);
        load(doc, text, src);
        const pugi::xml_node root = doc.document_element();
        const SourceLocation loc = src.at(root);
        if (std::string(root.name()) != "scene")
            throw LoadError(loc, "expected the root element <scene>, got <" + std::string(root.name()) + ">");
        const Attributes attrs = attributes(root, loc, {"version"}, {"version"});
        check_version(attrs.at("version"), loc);
        scene_.location = loc;
        parse_children(root, src, nullptr);
        resolve_refs(scene_.objects);
        return std::move(scene_);
    }

  private:
    static void load(pugi::xml_document& doc, const std::string& text, const Source& src) {
        const pugi::xml_parse_result result = doc.load_buffer(text.data(), text.size(), pugi::parse_default);
        if (!result)
            throw LoadError(src.at(result.offset), std::string("malformed XML: ") + result.description());
        if (!doc.document_element()) throw LoadError(src.at(0), "malformed XML: no root element");
    }

    // Replaces every `$name` by its define/default; an unknown name is an error naming it.
    std::string substitute(const std::string& value, const SourceLocation& loc,
                           const std::string& attr) const {
        std::string out;
        for (size_t i = 0; i < value.size();) {
            if (value[i] != '$') {
                out += value[i++];
                continue;
            }
            size_t j = i + 1;
            while (j < value.size() &&
                   (std::isalnum(static_cast<unsigned char>(value[j])) || value[j] == '_'))
                ++j;
            const std::string name = value.substr(i + 1, j - i - 1);
            const auto it = params_.find(name);
            if (name.empty() || it == params_.end())
                throw LoadError(loc, "undefined parameter '$" + name + "' in attribute '" + attr +
                                         "' (declare it with <default name=\"" + name +
                                         "\" value=\"...\"/> or define it on the command line)");
            out += it->second;
            i = j;
        }
        return out;
    }

    // Substituted attributes, checked against the allowed and required names.
    Attributes attributes(const pugi::xml_node& e, const SourceLocation& loc,
                          std::initializer_list<const char*> allowed,
                          std::initializer_list<const char*> required) const {
        Attributes out;
        for (const pugi::xml_attribute& a : e.attributes()) {
            const std::string name = a.name();
            if (std::none_of(allowed.begin(), allowed.end(), [&](const char* n) { return name == n; })) {
                std::string list;
                for (const char* n : allowed)
                    list += std::string(list.empty() ? "" : ", ") + n;
                throw LoadError(loc, "unexpected attribute '" + name + "' in <" + e.name() + "> (expected " +
                                         (list.empty() ? std::string("none") : list) + ")");
            }
            out[name] = substitute(a.value(), loc, name);
        }
        for (const char* r : required)
            if (!out.count(r))
                throw LoadError(loc, "missing attribute '" + std::string(r) + "' in <" + e.name() + ">");
        return out;
    }

    static void check_name(const std::string& name, const SourceLocation& loc, const char* what) {
        if (!name.empty() && name[0] == '_')
            throw LoadError(loc, std::string("invalid ") + what + " '" + name +
                                     "': a leading underscore is reserved for generated names");
    }

    void parse_children(const pugi::xml_node& e, const Source& src, XmlNode* parent) {
        for (const pugi::xml_node& child : e.children())
            parse_element(child, src, parent);
    }

    std::vector<XmlChild>& container(XmlNode* parent) { return parent ? parent->children : scene_.objects; }

    void parse_element(const pugi::xml_node& e, const Source& src, XmlNode* parent) {
        const SourceLocation loc = src.at(e);
        if (e.type() != pugi::node_element) {
            if (e.type() == pugi::node_pcdata || e.type() == pugi::node_cdata)
                throw LoadError(loc,
                                "unexpected text '" + std::string(e.value()) + "' (expected an XML element)");
            return; // declarations, processing instructions
        }
        const std::string tag = e.name();
        const auto obj = object_tags().find(tag);
        if (obj != object_tags().end() || (tag == "spectrum" && e.attribute("type")))
            parse_object(e, src, loc, obj != object_tags().end() ? obj->second : ObjectKind::Texture, parent);
        else if (is_value_tag(tag))
            parse_value(e, src, loc, parent);
        else if (tag == "ref")
            parse_ref(e, loc, parent);
        else if (tag == "default")
            parse_default(e, loc);
        else if (tag == "alias")
            parse_alias(e, loc);
        else if (tag == "path")
            parse_path(e, src, loc, parent);
        else if (tag == "include")
            parse_include(e, src, loc, parent);
        else if (tag == "volume") // a Mitsuba object kind penumbra does not model (grid/constant volumes)
            throw LoadError(loc, "unsupported volume plugin '" +
                                     attributes(e, loc, {"type", "id", "name"}, {"type"}).at("type") + "'");
        else if (is_transform_op(tag))
            throw LoadError(loc, "<" + tag + "> may only appear inside <transform>");
        else
            throw LoadError(loc,
                            "unexpected tag <" + tag +
                                "> (expected an object such as <shape> or <bsdf>, a value such as <float> or "
                                "<rgb>, <transform>, <ref>, <default>, <include>, <path> or <alias>)");
    }

    void parse_object(const pugi::xml_node& e, const Source& src, const SourceLocation& loc, ObjectKind kind,
                      XmlNode* parent) {
        const Attributes a = attributes(e, loc, {"type", "id", "name"}, {"type"});
        auto node = std::make_shared<XmlNode>();
        node->kind = kind;
        // Plugin names are matched case-insensitively: Mitsuba finds its plugins as files, so scenes written on
        // case-insensitive file systems (the docs' principled_blend_creation scenes use "Rectangle") load there.
        node->type = a.at("type");
        std::transform(node->type.begin(), node->type.end(), node->type.begin(),
                       [](unsigned char c) { return char(std::tolower(c)); });
        node->location = loc;
        node->props = Properties(node->type, loc);
        const std::string name = a.count("name") ? a.at("name") : std::string();
        check_name(name, loc, "name");
        if (a.count("id")) {
            node->id = a.at("id");
            check_name(node->id, loc, "id");
            register_id(node->id, node, loc);
        }
        parse_children(e, src, node.get());
        container(parent).push_back({name, "", node, loc});
    }

    void register_id(const std::string& id, const std::shared_ptr<XmlNode>& node, const SourceLocation& loc) {
        const auto it = scene_.ids.find(id);
        if (it != scene_.ids.end())
            throw LoadError(loc, "duplicate id '" + id + "' (first declared at " +
                                     it->second->location.str() + ")");
        scene_.ids[id] = node;
    }

    void parse_ref(const pugi::xml_node& e, const SourceLocation& loc, XmlNode* parent) {
        const Attributes a = attributes(e, loc, {"id", "name"}, {"id"});
        const std::string name = a.count("name") ? a.at("name") : std::string();
        check_name(name, loc, "name");
        container(parent).push_back({name, a.at("id"), nullptr, loc});
    }

    void parse_default(const pugi::xml_node& e, const SourceLocation& loc) {
        const Attributes a = attributes(e, loc, {"name", "value"}, {"name", "value"});
        if (a.at("name").empty()) throw LoadError(loc, "<default> needs a non-empty 'name'");
        params_.emplace(a.at("name"), a.at("value")); // defines and earlier defaults win
    }

    void parse_alias(const pugi::xml_node& e, const SourceLocation& loc) {
        const Attributes a = attributes(e, loc, {"id", "as"}, {"id", "as"});
        const auto it = scene_.ids.find(a.at("id"));
        if (it == scene_.ids.end()) throw LoadError(loc, "<alias> of unknown id '" + a.at("id") + "'");
        check_name(a.at("as"), loc, "id");
        register_id(a.at("as"), it->second, loc);
    }

    // Mitsuba: relative to the declaring file's directory first, otherwise against the search paths.
    void parse_path(const pugi::xml_node& e, const Source& src, const SourceLocation& loc,
                    const XmlNode* parent) {
        if (parent) throw LoadError(loc, "<path> may only appear directly inside <scene>");
        const std::string value = attributes(e, loc, {"value"}, {"value"}).at("value");
        std::string dir;
        if (fs::path(value).is_absolute()) {
            dir = value;
        } else {
            std::vector<std::string> candidates{(fs::path(src.dir) / value).lexically_normal().string()};
            for (const auto& p : scene_.search_paths)
                candidates.push_back((fs::path(p) / value).lexically_normal().string());
            for (const auto& c : candidates)
                if (is_directory(c)) {
                    dir = c;
                    break;
                }
        }
        if (dir.empty() || !is_directory(dir))
            throw LoadError(loc, "<path>: folder '" + value + "' not found");
        if (std::find(scene_.search_paths.begin(), scene_.search_paths.end(), dir) ==
            scene_.search_paths.end())
            scene_.search_paths.push_back(dir);
    }

    // A <scene> root splices its children into the including element; any other root is one child element.
    void parse_include(const pugi::xml_node& e, const Source& from, const SourceLocation& loc,
                       XmlNode* parent) {
        const std::string filename = attributes(e, loc, {"filename"}, {"filename"}).at("filename");
        std::vector<std::string> dirs = scene_.search_paths;
        dirs.push_back(from.dir);
        const std::string path = find_file(filename, dirs);
        if (path.empty())
            throw LoadError(loc, "included file '" + filename + "' not found in the search paths");
        const std::string key = fs::weakly_canonical(path).string();
        if (std::find(include_stack_.begin(), include_stack_.end(), key) != include_stack_.end()) {
            std::string chain;
            for (const auto& f : include_stack_)
                chain += f + " -> ";
            throw LoadError(loc, "include cycle: " + chain + key);
        }
        const std::string text = read_text_file(path);
        const Source src(path, fs::path(path).parent_path().string(), text);
        pugi::xml_document doc;
        load(doc, text, src);
        include_stack_.push_back(key);
        const pugi::xml_node root = doc.document_element();
        if (std::string(root.name()) == "scene") {
            const SourceLocation root_loc = src.at(root);
            const Attributes a = attributes(root, root_loc, {"version"}, {});
            if (a.count("version")) check_version(a.at("version"), root_loc);
            parse_children(root, src, parent);
        } else {
            parse_element(root, src, parent);
        }
        include_stack_.pop_back();
    }

    void parse_value(const pugi::xml_node& e, const Source& src, const SourceLocation& loc, XmlNode* parent) {
        const std::string tag = e.name();
        Properties& props = parent ? parent->props : scene_.props; // directly in <scene>: the scene's own
        if (tag == "transform") {
            const std::string name = attributes(e, loc, {"name"}, {"name"}).at("name");
            check_name(name, loc, "name");
            props.set(name, parse_transform(e, src), loc);
            return;
        }
        if (tag == "point" || tag == "vector") {
            const Attributes a = attributes(e, loc, {"name", "value", "x", "y", "z"}, {"name"});
            check_name(a.at("name"), loc, "name");
            props.set(a.at("name"), parse_xyz(e, a, loc, 0.f), loc);
            return;
        }
        if (tag == "spectrum") {
            const Attributes a = attributes(e, loc, {"name", "value", "filename"}, {"name"});
            check_name(a.at("name"), loc, "name");
            props.set(a.at("name"), ColorValue{parse_spectrum(a, loc, parent && parent->kind == ObjectKind::Emitter)},
                      loc);
            return;
        }
        const Attributes a = attributes(e, loc, {"name", "value"}, {"name", "value"});
        const std::string& name = a.at("name");
        const std::string& value = a.at("value");
        check_name(name, loc, "name");
        const std::string what = "<" + tag + " name=\"" + name + "\"> attribute 'value'";
        Properties::Value v;
        if (tag == "float") {
            v = parse_float(value, loc, what);
        } else if (tag == "integer") {
            v = parse_integer(value, loc, what);
        } else if (tag == "boolean") {
            std::string lower = value;
            std::transform(lower.begin(), lower.end(), lower.begin(),
                           [](unsigned char c) { return std::tolower(c); });
            if (lower != "true" && lower != "false")
                throw LoadError(loc, what + ": expected 'true' or 'false', got '" + value + "'");
            v = lower == "true";
        } else if (tag == "string") {
            v = value;
        } else { // rgb: one gray value or three components
            v = ColorValue{parse_vec3(value, loc, what, true)};
        }
        props.set(name, std::move(v), loc);
    }

    // x/y/z attributes (missing ones take `def`) or one `value` with 1 or 3 numbers.
    static Vec3f parse_xyz(const pugi::xml_node& e, const Attributes& a, const SourceLocation& loc,
                           float def) {
        const std::string tag = e.name();
        if (a.count("value")) {
            if (a.count("x") || a.count("y") || a.count("z"))
                throw LoadError(loc, "<" + tag + ">: use either 'value' or 'x'/'y'/'z', not both");
            return parse_vec3(a.at("value"), loc, "<" + tag + "> attribute 'value'", true);
        }
        Vec3f v(def);
        const char* axes[3] = {"x", "y", "z"};
        for (int i = 0; i < 3; ++i)
            if (a.count(axes[i]))
                v[i] = float(parse_float(a.at(axes[i]), loc, "<" + tag + "> attribute '" + axes[i] + "'"));
        return v;
    }

    // Constant (gray), `wavelength:value` list, or .spd file -> linear sRGB as in Mitsuba's RGB variants.
    Color3f parse_spectrum(const Attributes& a, const SourceLocation& loc, bool within_emitter) const {
        const std::string& name = a.at("name");
        const std::string what = "<spectrum name=\"" + name + "\">";
        if (a.count("value") == a.count("filename"))
            throw LoadError(loc, what + ": expected exactly one of the attributes 'value' and 'filename'");
        std::vector<std::pair<float, float>> samples;
        if (a.count("value")) {
            const auto tokens = tokenize(a.at("value"));
            if (tokens.size() == 1 && tokens[0].find(':') == std::string::npos)
                return Color3f(float(parse_float(tokens[0], loc, what + " attribute 'value'")));
            for (const auto& t : tokens) {
                const auto pair = tokenize(t, ":");
                if (pair.size() != 2 || t.find(':') != t.rfind(':'))
                    throw LoadError(loc, what + ": expected wavelength:value pairs, got '" + t + "'");
                samples.emplace_back(float(parse_float(pair[0], loc, what + " wavelength")),
                                     float(parse_float(pair[1], loc, what + " value")));
            }
        } else {
            const std::string path = find_file(a.at("filename"), scene_.search_paths);
            if (path.empty())
                throw LoadError(loc, what + ": spectrum file '" + a.at("filename") + "' not found");
            try {
                samples = read_spd(path);
            } catch (const Error& err) {
                throw LoadError(loc, what + ": " + err.what());
            }
        }
        if (samples.empty()) throw LoadError(loc, what + ": no spectral samples");
        for (size_t i = 1; i < samples.size(); ++i)
            if (samples[i].first <= samples[i - 1].first)
                throw LoadError(loc, what + ": wavelengths must be strictly increasing");
        // Mitsuba 3 (xml.cpp): reflectance-like spectra are integrated against CIE x D65 to match its spectral
        // modes; emission spectra are not (unless unbounded, e.g. an IOR inside an emitter).
        const bool unbounded = is_unbounded_spectrum(name);
        const bool bounded = !(within_emitter || unbounded);
        return spectrum_to_rgb(samples, bounded, /* d65 */ !(within_emitter && !unbounded));
    }

    Transform parse_transform(const pugi::xml_node& e, const Source& src) const {
        Transform t;
        for (const pugi::xml_node& op : e.children()) {
            const SourceLocation loc = src.at(op);
            const std::string tag = op.name();
            if (op.type() != pugi::node_element || !is_transform_op(tag))
                throw LoadError(
                    loc, "<transform> may only contain translate, rotate, scale, matrix and lookat (got " +
                             (op.type() == pugi::node_element ? "<" + tag + ">" : std::string("text")) + ")");
            t = parse_transform_op(op, tag, loc) * t;
        }
        return t;
    }

    Transform parse_transform_op(const pugi::xml_node& op, const std::string& tag,
                                 const SourceLocation& loc) const {
        if (tag == "translate") {
            const Attributes a = attributes(op, loc, {"value", "x", "y", "z"}, {});
            return Transform::translate(parse_xyz(op, a, loc, 0.f));
        }
        if (tag == "scale") {
            const Attributes a = attributes(op, loc, {"value", "x", "y", "z"}, {});
            return Transform::scale(parse_xyz(op, a, loc, 1.f));
        }
        if (tag == "rotate") {
            const Attributes a = attributes(op, loc, {"value", "x", "y", "z", "angle"}, {"angle"});
            const Vec3f axis = parse_xyz(op, a, loc, 0.f);
            if (axis == Vec3f(0.f))
                throw LoadError(loc, "<rotate>: expected a non-zero rotation axis (x, y, z)");
            return Transform::rotate(axis,
                                     float(parse_float(a.at("angle"), loc, "<rotate> attribute 'angle'")));
        }
        if (tag == "matrix") {
            // Row-major 4x4, or a 3x3 linear part (Mitsuba embeds it in the identity).
            const std::string value = attributes(op, loc, {"value"}, {"value"}).at("value");
            const auto tokens = tokenize(value);
            if (tokens.size() != 16 && tokens.size() != 9)
                throw LoadError(loc, "<matrix> attribute 'value': expected 16 (or 9) numbers, got " +
                                         std::to_string(tokens.size()));
            const int n = tokens.size() == 16 ? 4 : 3;
            Matrix4 m = Matrix4::identity();
            for (int i = 0; i < n; ++i)
                for (int j = 0; j < n; ++j)
                    m.m[i][j] =
                        float(parse_float(tokens[size_t(i * n + j)], loc, "<matrix> attribute 'value'"));
            try {
                return Transform(m);
            } catch (const std::runtime_error&) {
                throw LoadError(loc, "<matrix>: expected an invertible matrix");
            }
        }
        // lookat: a missing or zero `up` is replaced by a vector orthogonal to the view direction (Mitsuba).
        const Attributes a = attributes(op, loc, {"origin", "target", "up"}, {"origin", "target"});
        const Vec3f origin = parse_vec3(a.at("origin"), loc, "<lookat> attribute 'origin'", false);
        const Vec3f target = parse_vec3(a.at("target"), loc, "<lookat> attribute 'target'", false);
        Vec3f up = a.count("up") ? parse_vec3(a.at("up"), loc, "<lookat> attribute 'up'", false) : Vec3f(0.f);
        if (origin == target) throw LoadError(loc, "<lookat>: 'origin' and 'target' must differ");
        if (up == Vec3f(0.f)) {
            Vec3f unused;
            coordinate_system(normalize(target - origin), up, unused);
        }
        try {
            return Transform::look_at(origin, target, up);
        } catch (const std::runtime_error& err) {
            throw LoadError(loc, std::string("<lookat>: ") + err.what());
        }
    }

    void resolve_refs(std::vector<XmlChild>& children) const {
        for (auto& c : children) {
            if (c.ref_id.empty()) {
                resolve_refs(c.node->children);
                continue;
            }
            const auto it = scene_.ids.find(c.ref_id);
            if (it == scene_.ids.end())
                throw LoadError(c.location, "reference to unknown id '" + c.ref_id + "'");
            // A ref does not own its target (`ids` does): refs may point forward, so owning ones could form a
            // cycle (<bsdf id="a"><ref id="a"/></bsdf>, refused later by the loader) and leak the tree.
            c.node = std::shared_ptr<XmlNode>(std::shared_ptr<XmlNode>(), it->second.get());
        }
    }

    std::map<std::string, std::string> params_;
    std::vector<std::string> include_stack_; // canonical paths of the files being parsed
    XmlScene scene_;
};

} // namespace

XmlScene parse_xml_file(const std::string& path, const std::map<std::string, std::string>& defines) {
    if (!is_file(path)) throw LoadError({path, 0}, "cannot open scene file");
    const std::string text = read_text_file(path);
    std::string dir = fs::path(path).parent_path().string();
    Parser parser(defines, dir.empty() ? "." : dir);
    return parser.parse_root(text, path, fs::weakly_canonical(path).string());
}

XmlScene parse_xml_string(const std::string& xml, const std::string& base_dir,
                          const std::map<std::string, std::string>& defines) {
    Parser parser(defines, base_dir);
    return parser.parse_root(xml, "<string>", "<string>");
}

} // namespace penumbra
