// Mitsuba's .serialized mesh format (little endian). Per mesh: uint16 0x041C, uint16 version (3 or 4), then a
// zlib stream holding: uint32 flags, [v4: NUL-terminated name], uint64 vertex count, uint64 triangle count,
// positions, [normals], [texcoords], [colors] (float or double per the flags), uint32 indices.
// The file ends with the byte offset of every mesh (uint64 in v4, uint32 in v3) and a uint32 mesh count.
// As in Mitsuba 3, the FaceNormals flag is ignored (only the shape's `face_normals` parameter counts) and
// vertex colors are skipped.
#include "scene/mesh.h"

#include "core/error.h"

#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <fstream>

namespace penumbra {
namespace {

constexpr uint16_t SerializedMagic = 0x041C;
enum SerializedFlags : uint32_t {
    HasNormals = 0x0001,
    HasTexcoords = 0x0002,
    HasColors = 0x0008,
    DoublePrecision = 0x2000,
};

// Little-endian scalar stored at p.
template <typename V> V load_le(const unsigned char* p) {
    unsigned char bytes[sizeof(V)];
    std::memcpy(bytes, p, sizeof(V));
    if constexpr (std::endian::native == std::endian::big)
        for (size_t i = 0; i < sizeof(V) / 2; ++i)
            std::swap(bytes[i], bytes[sizeof(V) - 1 - i]);
    V v;
    std::memcpy(&v, bytes, sizeof(V));
    return v;
}

// Inflates the zlib stream starting at `begin` until its end marker.
std::vector<unsigned char> inflate_stream(const std::vector<unsigned char>& file, size_t begin,
                                          const std::string& path) {
    z_stream zs{};
    if (inflateInit(&zs) != Z_OK) throw Error(path + ": zlib initialization failed");
    zs.next_in = const_cast<Bytef*>(file.data() + begin);
    zs.avail_in = uInt(file.size() - begin);
    std::vector<unsigned char> out(std::max<size_t>(4096, 4 * (file.size() - begin)));
    int status = Z_OK;
    while (status != Z_STREAM_END) {
        if (zs.total_out == out.size()) out.resize(out.size() * 2);
        zs.next_out = out.data() + zs.total_out;
        zs.avail_out = uInt(out.size() - zs.total_out);
        status = inflate(&zs, Z_NO_FLUSH);
        if (status != Z_OK && status != Z_STREAM_END) {
            const std::string msg =
                status == Z_BUF_ERROR ? "truncated compressed data" : "corrupt compressed data";
            inflateEnd(&zs);
            throw Error(path + ": " + msg);
        }
    }
    out.resize(zs.total_out);
    inflateEnd(&zs);
    return out;
}

// Sequential reader of the decompressed mesh record.
struct RecordReader {
    const std::vector<unsigned char>& data;
    const std::string& path;
    size_t pos = 0;

    const unsigned char* take(size_t n, const char* what) {
        if (n > data.size() - pos) throw Error(path + ": mesh data ends while reading " + std::string(what));
        const unsigned char* p = data.data() + pos;
        pos += n;
        return p;
    }
    template <typename V> V read(const char* what) { return load_le<V>(take(sizeof(V), what)); }
    // `count * dim` reals stored as float or double.
    std::vector<float> reals(size_t count, size_t dim, bool double_precision, const char* what) {
        const size_t n = count * dim, size = double_precision ? 8 : 4;
        if (count != 0 && n / count != dim) throw Error(path + ": invalid vertex count");
        const unsigned char* p = take(n * size, what);
        std::vector<float> v(n);
        for (size_t i = 0; i < n; ++i)
            v[i] = double_precision ? float(load_le<double>(p + 8 * i)) : load_le<float>(p + 4 * i);
        return v;
    }
};

} // namespace

TriangleMesh load_serialized(const std::string& path, int shape_index) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(path + ": cannot open serialized mesh file");
    const std::vector<unsigned char> file((std::istreambuf_iterator<char>(in)),
                                          std::istreambuf_iterator<char>());
    if (shape_index < 0) throw Error(path + ": shape_index must be non-negative");
    if (file.size() < 8) throw Error(path + ": file too short to be a serialized mesh");
    const uint16_t version = load_le<uint16_t>(file.data() + 2);
    if (load_le<uint16_t>(file.data()) != SerializedMagic)
        throw Error(path + ": not a serialized mesh file (bad header identifier)");
    if (version != 3 && version != 4)
        throw Error(path + ": unsupported serialized format version " + std::to_string(version) +
                    " (expected 3 or 4)");

    // Locate the mesh through the end-of-file dictionary.
    const uint32_t count = load_le<uint32_t>(file.data() + file.size() - 4);
    if (uint32_t(shape_index) >= count)
        throw Error(path + ": shape_index " + std::to_string(shape_index) +
                    " is out of range (the file holds " + std::to_string(count) + " meshes)");
    const size_t entry = version == 4 ? 8 : 4;
    if (size_t(count) * entry + 4 > file.size()) throw Error(path + ": corrupt end-of-file mesh dictionary");
    const unsigned char* slot = file.data() + file.size() - 4 - entry * (count - uint32_t(shape_index));
    const uint64_t offset = version == 4 ? load_le<uint64_t>(slot) : load_le<uint32_t>(slot);
    if (offset > file.size() - 4 || load_le<uint16_t>(file.data() + offset) != SerializedMagic)
        throw Error(path + ": mesh " + std::to_string(shape_index) + " has an invalid file offset");

    const std::vector<unsigned char> record = inflate_stream(file, size_t(offset) + 4, path);
    RecordReader r{record, path};
    const uint32_t flags = r.read<uint32_t>("the flags");
    if (version == 4)
        while (r.read<char>("the mesh name") != '\0') {
        }
    const uint64_t vertex_count = r.read<uint64_t>("the vertex count");
    const uint64_t face_count = r.read<uint64_t>("the triangle count");
    if (vertex_count > 0xFFFFFFFFull)
        throw Error(path + ": meshes with more than 2^32 vertices are not supported");
    const bool dp = (flags & DoublePrecision) != 0;

    TriangleMesh mesh;
    const std::vector<float> p = r.reals(vertex_count, 3, dp, "vertex positions");
    mesh.positions.resize(vertex_count);
    for (size_t i = 0; i < vertex_count; ++i)
        mesh.positions[i] = Vec3f(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
    if (flags & HasNormals) {
        const std::vector<float> n = r.reals(vertex_count, 3, dp, "vertex normals");
        mesh.normals.resize(vertex_count);
        for (size_t i = 0; i < vertex_count; ++i)
            mesh.normals[i] = Vec3f(n[3 * i], n[3 * i + 1], n[3 * i + 2]);
    }
    if (flags & HasTexcoords) {
        const std::vector<float> t = r.reals(vertex_count, 2, dp, "texture coordinates");
        mesh.uvs.resize(vertex_count);
        for (size_t i = 0; i < vertex_count; ++i)
            mesh.uvs[i] = Vec2f(t[2 * i], t[2 * i + 1]);
    }
    if (flags & HasColors) r.take(vertex_count * 3 * (dp ? 8 : 4), "vertex colors");
    if (face_count > (record.size() - r.pos) / 12)
        throw Error(path + ": mesh data ends while reading triangle indices");
    const unsigned char* idx = r.take(face_count * 12, "triangle indices");
    mesh.indices.resize(face_count * 3);
    for (size_t i = 0; i < face_count * 3; ++i)
        mesh.indices[i] = load_le<uint32_t>(idx + 4 * i);
    mesh.validate(path + "@" + std::to_string(shape_index));
    return mesh;
}

} // namespace penumbra
