// Triangle meshes: the one geometric representation of every shape (analytic shapes are tessellated).
#pragma once
#include "core/transform.h"

#include <cstdint>
#include <string>
#include <vector>

namespace penumbra {

// A Mitsuba mesh attribute: `dim` floats per vertex ("vertex_<name>") or per triangle ("face_<name>").
struct MeshAttribute {
    std::string name;
    int dim = 1;
    std::vector<float> values;
};

struct TriangleMesh {
    std::vector<Vec3f> positions;
    std::vector<Vec3f> normals;    // per-vertex shading normals (empty: use face normals)
    std::vector<Vec2f> uvs;        // per-vertex texture coordinates (empty: uv = barycentrics)
    std::vector<uint32_t> indices; // 3 per triangle
    std::vector<MeshAttribute> attributes; // extra PLY properties, named as Mitsuba names them

    // The attribute called `name`, or nullptr.
    const MeshAttribute* attribute(const std::string& name) const;

    size_t vertex_count() const { return positions.size(); }
    size_t face_count() const { return indices.size() / 3; }
    void apply_transform(const Transform& to_world); // positions, normals (renormalized)
    // Throws penumbra::Error("<context>: <what is wrong>") on out-of-range indices, non-finite data,
    // attribute count mismatch (normals, uvs, mesh attributes) or an empty mesh.
    void validate(const std::string& context) const;
};

// Smooth vertex normals (replacing any present): the angle-weighted sum of the incident face normals, as
// Mitsuba 3 computes them for meshes loaded without normals.
void recompute_vertex_normals(TriangleMesh& mesh);

// Loaders; every error names the file (and line for text formats).
TriangleMesh load_obj(const std::string& path);
TriangleMesh load_ply(const std::string& path);
// Mitsuba's .serialized format; `shape_index` selects one mesh of a multi-mesh file.
TriangleMesh load_serialized(const std::string& path, int shape_index);

// Tessellated primitives in their Mitsuba 3 canonical frames.
TriangleMesh make_rectangle_mesh();        // [-1,1]^2 at z=0, normal +z
TriangleMesh make_cube_mesh();             // [-1,1]^3, outward normals, 24 vertices
TriangleMesh make_disk_mesh(int segments); // unit disk at z=0, normal +z
TriangleMesh make_sphere_mesh(const Vec3f& center, float radius, int rings, int segments);

} // namespace penumbra
