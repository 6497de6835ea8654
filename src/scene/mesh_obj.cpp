// Wavefront OBJ reader (parsing by tinyobjloader). As in Mitsuba 3, every distinct (position, texcoord,
// normal) index triple becomes one vertex, all groups are merged into one mesh, materials are ignored and
// polygons are fan-triangulated (v0, v[k-1], v[k]). Texture coordinates are returned as stored in the file
// (the `flip_tex_coords` convention is applied by the shape factory).
#include "scene/mesh.h"

#include "core/error.h"

#include <tiny_obj_loader.h>

#include <array>
#include <fstream>
#include <unordered_map>

namespace penumbra {
namespace {

struct IndexTripleHash {
    size_t operator()(const std::array<int, 3>& k) const {
        size_t h = std::hash<int>()(k[0]);
        h = h * 1000003u ^ std::hash<int>()(k[1]);
        return h * 1000003u ^ std::hash<int>()(k[2]);
    }
};

std::string first_line(const std::string& s) {
    const size_t end = s.find('\n');
    return end == std::string::npos ? s : s.substr(0, end);
}

} // namespace

TriangleMesh load_obj(const std::string& path) {
    std::ifstream file(path);
    if (!file) throw Error(path + ": cannot open OBJ file");
    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::vector<tinyobj::material_t> materials;
    std::string warn, err;
    // No material reader: `mtllib` statements are ignored. No triangulation: we fan-triangulate below.
    if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &file, nullptr, false))
        throw Error(path + ": " + (err.empty() ? std::string("invalid OBJ file") : first_line(err)));

    const size_t np = attrib.vertices.size() / 3, nt = attrib.texcoords.size() / 2,
                 nn = attrib.normals.size() / 3;
    // First pass: decide whether every corner has a texture coordinate / normal (otherwise drop that
    // attribute).
    bool all_uv = true, all_n = true;
    size_t corners = 0;
    for (const auto& shape : shapes)
        for (const auto& idx : shape.mesh.indices) {
            all_uv &= idx.texcoord_index >= 0;
            all_n &= idx.normal_index >= 0;
            ++corners;
        }
    if (corners == 0) throw Error(path + ": OBJ file contains no faces");

    TriangleMesh mesh;
    std::unordered_map<std::array<int, 3>, uint32_t, IndexTripleHash> vertex_of;
    auto vertex = [&](const tinyobj::index_t& idx, size_t face) -> uint32_t {
        auto check = [&](int i, size_t n, const char* what) {
            if (i < 0 || size_t(i) >= n)
                throw Error(path + ": face " + std::to_string(face) + " references " + what + " " +
                            std::to_string(i + 1) + " but the file defines " + std::to_string(n));
        };
        check(idx.vertex_index, np, "vertex");
        const std::array<int, 3> key{idx.vertex_index, all_uv ? idx.texcoord_index : -1,
                                     all_n ? idx.normal_index : -1};
        auto [it, inserted] = vertex_of.try_emplace(key, uint32_t(mesh.positions.size()));
        if (!inserted) return it->second;
        const float* p = &attrib.vertices[3 * size_t(key[0])];
        mesh.positions.emplace_back(p[0], p[1], p[2]);
        if (all_uv) {
            check(key[1], nt, "texture coordinate");
            const float* t = &attrib.texcoords[2 * size_t(key[1])];
            mesh.uvs.emplace_back(t[0], t[1]);
        }
        if (all_n) {
            check(key[2], nn, "normal");
            const float* n = &attrib.normals[3 * size_t(key[2])];
            mesh.normals.emplace_back(n[0], n[1], n[2]);
        }
        return it->second;
    };

    size_t face = 0;
    for (const auto& shape : shapes) {
        size_t offset = 0;
        for (const unsigned char count : shape.mesh.num_face_vertices) {
            if (count < 3)
                throw Error(path + ": face " + std::to_string(face) + " has " + std::to_string(count) +
                            " vertices (at least 3 are needed)");
            const tinyobj::index_t* c = &shape.mesh.indices[offset];
            const uint32_t v0 = vertex(c[0], face);
            uint32_t prev = vertex(c[1], face);
            for (size_t k = 2; k < count; ++k) {
                const uint32_t v = vertex(c[k], face);
                mesh.indices.insert(mesh.indices.end(), {v0, prev, v});
                prev = v;
            }
            offset += count;
            ++face;
        }
    }
    mesh.validate(path);
    return mesh;
}

} // namespace penumbra
