// PLY (Stanford polygon file) reader: ascii, binary_little_endian and binary_big_endian bodies.
// Vertex properties: x, y, z; optional nx, ny, nz; texture coordinates as u/v, texture_u/texture_v or s/t
// (Mitsuba 3's order of preference). Faces: a `vertex_indices` or `vertex_index` list of any integer type;
// polygons are fan-triangulated (v0, v[k-1], v[k]). Other scalar vertex/face properties become Mitsuba mesh
// attributes (group_attributes); list properties and other elements are skipped by their size.
#include "scene/mesh.h"

#include "core/error.h"
#include "core/image.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

namespace penumbra {
namespace {

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };
enum class PlyFormat { Ascii, BinaryLittleEndian, BinaryBigEndian };

struct PlyProperty {
    std::string name;
    PlyType type = PlyType::Float32;
    bool is_list = false;
    PlyType count_type = PlyType::UInt8; // lists only
};

struct PlyElement {
    std::string name;
    size_t count = 0;
    int line = 0; // of its declaration in the header
    std::vector<PlyProperty> properties;
    int index_of(const std::string& name) const {
        for (size_t i = 0; i < properties.size(); ++i)
            if (properties[i].name == name) return int(i);
        return -1;
    }
};

struct PlyHeader {
    PlyFormat format = PlyFormat::Ascii;
    std::vector<PlyElement> elements;
    size_t body_offset = 0; // first byte after "end_header\n"
    int body_line = 0;      // line number of the first body line (ascii)
};

[[noreturn]] void fail(const std::string& path, int line, const std::string& msg) {
    throw Error(path + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " + msg);
}

bool parse_type(const std::string& s, PlyType& t) {
    static const std::pair<const char*, PlyType> names[] = {
        {"char", PlyType::Int8},      {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
        {"uint8", PlyType::UInt8},    {"short", PlyType::Int16},     {"int16", PlyType::Int16},
        {"ushort", PlyType::UInt16},  {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
        {"int32", PlyType::Int32},    {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
        {"float", PlyType::Float32},  {"float32", PlyType::Float32}, {"double", PlyType::Float64},
        {"float64", PlyType::Float64}};
    for (const auto& [name, type] : names)
        if (s == name) {
            t = type;
            return true;
        }
    return false;
}

size_t type_size(PlyType t) {
    switch (t) {
    case PlyType::Int8:
    case PlyType::UInt8:
        return 1;
    case PlyType::Int16:
    case PlyType::UInt16:
        return 2;
    case PlyType::Int32:
    case PlyType::UInt32:
    case PlyType::Float32:
        return 4;
    case PlyType::Float64:
        return 8;
    }
    return 0;
}

bool is_integer(PlyType t) { return t != PlyType::Float32 && t != PlyType::Float64; }

PlyHeader parse_header(const std::string& data, const std::string& path) {
    PlyHeader header;
    size_t pos = 0;
    int line_no = 0;
    bool have_format = false;
    auto next_line = [&](std::string& line) {
        if (pos >= data.size()) return false;
        size_t end = data.find('\n', pos);
        if (end == std::string::npos) end = data.size();
        line = data.substr(pos, end - pos);
        if (!line.empty() && line.back() == '\r') line.pop_back();
        pos = end + 1;
        ++line_no;
        return true;
    };
    std::string line;
    if (!next_line(line) || line != "ply") fail(path, 1, "not a PLY file (the first line must be 'ply')");
    while (true) {
        if (!next_line(line)) fail(path, line_no, "header ends without 'end_header'");
        std::istringstream in(line);
        std::string keyword;
        in >> keyword;
        if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
        if (keyword == "end_header") break;
        if (keyword == "format") {
            std::string fmt, version;
            in >> fmt >> version;
            if (fmt == "ascii")
                header.format = PlyFormat::Ascii;
            else if (fmt == "binary_little_endian")
                header.format = PlyFormat::BinaryLittleEndian;
            else if (fmt == "binary_big_endian")
                header.format = PlyFormat::BinaryBigEndian;
            else
                fail(path, line_no,
                     "unsupported format '" + fmt +
                         "' (expected ascii, binary_little_endian or binary_big_endian)");
            have_format = true;
        } else if (keyword == "element") {
            PlyElement el;
            long long count = -1;
            in >> el.name >> count;
            if (el.name.empty() || !in || count < 0)
                fail(path, line_no, "malformed element declaration (expected 'element <name> <count>')");
            el.count = size_t(count);
            el.line = line_no;
            header.elements.push_back(std::move(el));
        } else if (keyword == "property") {
            if (header.elements.empty()) fail(path, line_no, "property declared before any element");
            PlyProperty prop;
            std::string type;
            in >> type;
            if (type == "list") {
                std::string count_type, item_type;
                in >> count_type >> item_type >> prop.name;
                prop.is_list = true;
                if (!parse_type(count_type, prop.count_type) || !is_integer(prop.count_type))
                    fail(path, line_no,
                         "invalid list count type '" + count_type + "' (expected an integer type)");
                if (!parse_type(item_type, prop.type))
                    fail(path, line_no, "unknown property type '" + item_type + "'");
            } else {
                in >> prop.name;
                if (!parse_type(type, prop.type)) fail(path, line_no, "unknown property type '" + type + "'");
            }
            if (prop.name.empty()) fail(path, line_no, "property without a name");
            header.elements.back().properties.push_back(prop);
        } else {
            fail(path, line_no, "unexpected header keyword '" + keyword + "'");
        }
    }
    if (!have_format) fail(path, line_no, "header has no 'format' line");
    header.body_offset = pos;
    header.body_line = line_no + 1;
    // A record takes at least one byte (binary) or two (ascii: a digit and a separator): a larger count is
    // corrupt, and is rejected before anything is allocated for it or a loop runs over it.
    const size_t body_bytes = data.size() - std::min(pos, data.size());
    for (const PlyElement& el : header.elements)
        if (el.count > body_bytes)
            fail(path, el.line,
                 "element '" + el.name + "' declares " + std::to_string(el.count) + " records, but only " +
                     std::to_string(body_bytes) + " bytes follow the header");
    return header;
}

// Sequential reader of body values; errors name the element and record being read.
class BodyReader {
  public:
    BodyReader(const std::string& data, const PlyHeader& header, const std::string& path)
        : data_(data), format_(header.format), pos_(header.body_offset), line_(header.body_line),
          path_(path) {}

    void set_record(const std::string& element, size_t index, size_t count) {
        element_ = &element;
        index_ = index;
        count_ = count;
    }

    double read(PlyType type) { return format_ == PlyFormat::Ascii ? read_ascii(type) : read_binary(type); }
    size_t remaining() const { return data_.size() - pos_; }

    [[noreturn]] void error(const std::string& msg) const {
        fail(path_, format_ == PlyFormat::Ascii ? line_ : 0,
             msg + " in element '" + *element_ + "' " + std::to_string(index_) + " of " +
                 std::to_string(count_));
    }

  private:
    double read_ascii(PlyType type) {
        while (pos_ < data_.size() && std::isspace(static_cast<unsigned char>(data_[pos_]))) {
            if (data_[pos_] == '\n') ++line_;
            ++pos_;
        }
        if (pos_ >= data_.size()) error("unexpected end of file");
        const char* begin = data_.c_str() + pos_;
        char* end = nullptr;
        const double v = std::strtod(begin, &end);
        const size_t used = size_t(end - begin);
        if (used == 0 || (pos_ + used < data_.size() && !std::isspace(static_cast<unsigned char>(*end)))) {
            size_t token_end = pos_;
            while (token_end < data_.size() && !std::isspace(static_cast<unsigned char>(data_[token_end])))
                ++token_end;
            error("invalid number '" + data_.substr(pos_, token_end - pos_) + "'");
        }
        if (is_integer(type) && v != std::floor(v)) error("non-integer value for an integer property");
        pos_ += used;
        return v;
    }

    double read_binary(PlyType type) {
        const size_t n = type_size(type);
        if (pos_ + n > data_.size()) error("truncated binary data (unexpected end of file)");
        unsigned char bytes[8];
        std::memcpy(bytes, data_.data() + pos_, n);
        pos_ += n;
        const bool file_little = format_ == PlyFormat::BinaryLittleEndian;
        if (file_little != (std::endian::native == std::endian::little))
            for (size_t i = 0; i < n / 2; ++i)
                std::swap(bytes[i], bytes[n - 1 - i]);
        switch (type) {
        case PlyType::Int8:
            return double(static_cast<int8_t>(bytes[0]));
        case PlyType::UInt8:
            return double(bytes[0]);
        case PlyType::Int16:
            return double(from_bytes<int16_t>(bytes));
        case PlyType::UInt16:
            return double(from_bytes<uint16_t>(bytes));
        case PlyType::Int32:
            return double(from_bytes<int32_t>(bytes));
        case PlyType::UInt32:
            return double(from_bytes<uint32_t>(bytes));
        case PlyType::Float32:
            return double(from_bytes<float>(bytes));
        case PlyType::Float64:
            return from_bytes<double>(bytes);
        }
        return 0.0;
    }

    template <typename V> static V from_bytes(const unsigned char* bytes) {
        V v;
        std::memcpy(&v, bytes, sizeof(V));
        return v;
    }

    const std::string& data_;
    PlyFormat format_;
    size_t pos_;
    int line_;
    const std::string& path_;
    const std::string* element_ = nullptr;
    size_t index_ = 0, count_ = 0;
};

// Mesh attributes from the scalar properties outside `reserved`, grouped as Mitsuba 3's PLY loader documents:
// consecutive <p>_{x,y,z,w}, <p>_{r,g,b,a}, <p>_{0,1,2,3} or <p>_{1,2,3,4} form "<prefix><p>" (dim = their
// number); bare r,g,b[,a] or red,green,blue[,alpha] form "<prefix>color"; any other is "<prefix><name>".
// slot[k] = (attribute index, component) for property k, or (-1, 0).
std::vector<MeshAttribute> group_attributes(const PlyElement& el, const std::string& prefix,
                                            const std::set<std::string>& reserved,
                                            std::vector<std::pair<int, int>>& slot) {
    static const std::vector<std::vector<std::string>> suffixes = {
        {"x", "y", "z", "w"}, {"r", "g", "b", "a"}, {"0", "1", "2", "3"}, {"1", "2", "3", "4"}};
    static const std::vector<std::vector<std::string>> colors = {{"r", "g", "b", "a"},
                                                                 {"red", "green", "blue", "alpha"}};
    std::vector<MeshAttribute> attributes;
    slot.assign(el.properties.size(), {-1, 0});
    auto usable = [&](size_t k) {
        return k < el.properties.size() && !el.properties[k].is_list &&
               !reserved.count(el.properties[k].name);
    };
    // Length of the run of properties from k named head + scheme[0], head + scheme[1], ...
    auto run = [&](size_t k, const std::string& head, const std::vector<std::string>& scheme) {
        size_t n = 0;
        while (n < scheme.size() && usable(k + n) && el.properties[k + n].name == head + scheme[n])
            ++n;
        return n;
    };
    for (size_t k = 0; k < el.properties.size();) {
        if (!usable(k)) {
            ++k;
            continue;
        }
        const std::string& name = el.properties[k].name;
        std::string attribute = name;
        size_t n = 1;
        for (const auto& scheme : colors)
            if (const size_t m = run(k, "", scheme); m >= 3 && n == 1) {
                n = m;
                attribute = "color";
            }
        const size_t underscore = name.rfind('_');
        if (n == 1 && underscore != std::string::npos && underscore > 0)
            for (const auto& scheme : suffixes)
                if (const size_t m = run(k, name.substr(0, underscore + 1), scheme); m >= 2 && n == 1) {
                    n = m;
                    attribute = name.substr(0, underscore);
                }
        for (size_t c = 0; c < n; ++c)
            slot[k + c] = {int(attributes.size()), int(c)};
        attributes.push_back({prefix + attribute, int(n), {}});
        k += n;
    }
    return attributes;
}

// Integer properties are normalized to [0, 1] and sRGB-decoded (Mitsuba flags them Normalized | Gamma).
float attribute_value(double v, PlyType type) {
    static const double max[] = {127.0, 255.0, 32767.0, 65535.0, 2147483647.0, 4294967295.0};
    return is_integer(type) ? srgb_to_linear(float(v / max[int(type)])) : float(v);
}

// Reads the length prefix of a list property.
size_t list_count(BodyReader& reader, const PlyProperty& prop) {
    const double n = reader.read(prop.count_type);
    if (n < 0) reader.error("negative list length for property '" + prop.name + "'");
    // Each item takes at least a byte: a longer list is corrupt (and its length may not even fit a size_t).
    if (n > double(reader.remaining())) {
        std::ostringstream length;
        length << n;
        reader.error("list length " + length.str() + " of property '" + prop.name +
                     "' exceeds the rest of the file");
    }
    return size_t(n);
}

void read_vertices(BodyReader& reader, const PlyElement& el, TriangleMesh& mesh, const std::string& path) {
    const int ix = el.index_of("x"), iy = el.index_of("y"), iz = el.index_of("z");
    if (ix < 0 || iy < 0 || iz < 0) fail(path, 0, "element 'vertex' lacks one of the properties x, y, z");
    const int inx = el.index_of("nx"), iny = el.index_of("ny"), inz = el.index_of("nz");
    const bool has_normals = inx >= 0 && iny >= 0 && inz >= 0;
    int iu = -1, iv = -1;
    for (const auto& [u, v] : {std::pair{"u", "v"}, std::pair{"texture_u", "texture_v"}, std::pair{"s", "t"}})
        if (iu < 0 && el.index_of(u) >= 0 && el.index_of(v) >= 0) {
            iu = el.index_of(u);
            iv = el.index_of(v);
        }
    // slot[k]: which component of (position, normal, uv) property k fills; -1 = skipped.
    std::vector<int> slot(el.properties.size(), -1);
    const int targets[] = {ix, iy, iz, has_normals ? inx : -1, has_normals ? iny : -1, has_normals ? inz : -1,
                           iu, iv};
    for (int k = 0; k < 8; ++k)
        if (targets[k] >= 0) {
            if (el.properties[size_t(targets[k])].is_list)
                fail(path, 0,
                     "vertex property '" + el.properties[size_t(targets[k])].name + "' must not be a list");
            slot[size_t(targets[k])] = k;
        }
    std::set<std::string> reserved = {"x", "y", "z", "nx", "ny", "nz"};
    if (iu >= 0) reserved.insert({el.properties[size_t(iu)].name, el.properties[size_t(iv)].name});
    std::vector<std::pair<int, int>> attribute_slot;
    std::vector<MeshAttribute> attributes = group_attributes(el, "vertex_", reserved, attribute_slot);
    for (MeshAttribute& a : attributes)
        a.values.resize(el.count * size_t(a.dim));
    mesh.positions.resize(el.count);
    if (has_normals) mesh.normals.resize(el.count);
    if (iu >= 0) mesh.uvs.resize(el.count);
    float values[8] = {};
    for (size_t i = 0; i < el.count; ++i) {
        reader.set_record(el.name, i, el.count);
        for (size_t k = 0; k < el.properties.size(); ++k) {
            const PlyProperty& prop = el.properties[k];
            if (prop.is_list) {
                for (size_t n = list_count(reader, prop); n > 0; --n)
                    reader.read(prop.type);
            } else {
                const double v = reader.read(prop.type);
                if (slot[k] >= 0) values[slot[k]] = float(v);
                if (const auto [a, c] = attribute_slot[k]; a >= 0)
                    attributes[size_t(a)].values[i * size_t(attributes[size_t(a)].dim) + size_t(c)] =
                        attribute_value(v, prop.type);
            }
        }
        mesh.positions[i] = Vec3f(values[0], values[1], values[2]);
        if (has_normals) mesh.normals[i] = Vec3f(values[3], values[4], values[5]);
        if (iu >= 0) mesh.uvs[i] = Vec2f(values[6], values[7]);
    }
    for (MeshAttribute& a : attributes)
        mesh.attributes.push_back(std::move(a));
}

void read_faces(BodyReader& reader, const PlyElement& el, TriangleMesh& mesh, const std::string& path) {
    int iidx = el.index_of("vertex_indices");
    if (iidx < 0) iidx = el.index_of("vertex_index");
    if (iidx < 0 || !el.properties[size_t(iidx)].is_list)
        fail(path, 0, "element 'face' has no 'vertex_indices' (or 'vertex_index') list property");
    if (!is_integer(el.properties[size_t(iidx)].type))
        fail(path, 0, "face indices must have an integer type");
    mesh.indices.reserve(el.count * 3);
    std::vector<std::pair<int, int>> attribute_slot;
    std::vector<MeshAttribute> attributes =
        group_attributes(el, "face_", {"vertex_indices", "vertex_index"}, attribute_slot);
    std::vector<std::vector<float>> record(attributes.size()); // this polygon's values, one per triangle
    for (size_t a = 0; a < attributes.size(); ++a)
        record[a].resize(size_t(attributes[a].dim));
    std::vector<uint32_t> polygon;
    for (size_t i = 0; i < el.count; ++i) {
        reader.set_record(el.name, i, el.count);
        const size_t first_triangle = mesh.face_count();
        for (size_t k = 0; k < el.properties.size(); ++k) {
            const PlyProperty& prop = el.properties[k];
            if (!prop.is_list) {
                const double v = reader.read(prop.type);
                if (const auto [a, c] = attribute_slot[k]; a >= 0)
                    record[size_t(a)][size_t(c)] = attribute_value(v, prop.type);
                continue;
            }
            const size_t n = list_count(reader, prop);
            if (int(k) != iidx) {
                for (size_t j = 0; j < n; ++j)
                    reader.read(prop.type);
                continue;
            }
            if (n < 3) reader.error("a face has " + std::to_string(n) + " vertices (at least 3 are needed)");
            polygon.resize(n);
            for (size_t j = 0; j < n; ++j) {
                const double v = reader.read(prop.type);
                if (v < 0 || v > double(UINT32_MAX))
                    reader.error("vertex index " + std::to_string(v) + " out of range");
                polygon[j] = uint32_t(v);
            }
            for (size_t j = 2; j < n; ++j)
                mesh.indices.insert(mesh.indices.end(), {polygon[0], polygon[j - 1], polygon[j]});
        }
        for (size_t a = 0; a < attributes.size(); ++a)
            for (size_t t = first_triangle; t < mesh.face_count(); ++t)
                attributes[a].values.insert(attributes[a].values.end(), record[a].begin(), record[a].end());
    }
    for (MeshAttribute& a : attributes)
        mesh.attributes.push_back(std::move(a));
}

} // namespace

TriangleMesh load_ply(const std::string& path) {
    std::ifstream file(path, std::ios::binary);
    if (!file) throw Error(path + ": cannot open PLY file");
    const std::string data((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    const PlyHeader header = parse_header(data, path);

    TriangleMesh mesh;
    BodyReader reader(data, header, path);
    bool have_vertices = false, have_faces = false;
    for (const PlyElement& el : header.elements) {
        if (el.name == "vertex") {
            read_vertices(reader, el, mesh, path);
            have_vertices = true;
        } else if (el.name == "face") {
            read_faces(reader, el, mesh, path);
            have_faces = true;
        } else {
            for (size_t i = 0; i < el.count; ++i) {
                reader.set_record(el.name, i, el.count);
                for (const PlyProperty& prop : el.properties)
                    for (size_t n = prop.is_list ? list_count(reader, prop) : 1; n > 0; --n)
                        reader.read(prop.type);
            }
        }
    }
    if (!have_vertices) fail(path, 0, "no 'vertex' element");
    if (!have_faces) fail(path, 0, "no 'face' element (not a triangle mesh)");
    mesh.validate(path);
    return mesh;
}

} // namespace penumbra
