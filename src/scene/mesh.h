// Triangle meshes: the one geometric representation of every shape (analytic shapes are tessellated).
#pragma once
#include "core/transform.h"

#include <cmath>
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
// Mitsuba 3 computes them for meshes loaded without normals and whenever their vertex_positions change.
void recompute_vertex_normals(TriangleMesh& mesh);

// Angle between unit vectors, stable for small and large angles: 2 asin(|a - b| / 2).
template <typename T> T unit_angle(const Vec3<T>& a, const Vec3<T>& b) {
    using std::asin;
    return detach(dot(a, b)) < 0.f ? T(Pi) - T(2.f) * asin(T(0.5f) * norm(a + b))
                                   : T(2.f) * asin(T(0.5f) * norm(a - b));
}

// The term of triangle (p[0], p[1], p[2]) in the smooth normal of its corner k (Thuermer & Wuethrich 1998, as
// Mitsuba 3): its unit face normal times the corner's angle; zero for a degenerate face or corner. Templated so
// that the estimators differentiate the normals through the positions with the same formula.
template <typename T> Vec3<T> corner_normal(const Vec3<T> (&p)[3], int k) {
    const Vec3<T> n = cross(p[1] - p[0], p[2] - p[0]);
    const T length = norm(n);
    const Vec3<T> e1 = p[(k + 1) % 3] - p[k], e2 = p[(k + 2) % 3] - p[k];
    const T l1 = norm(e1), l2 = norm(e2);
    if (!(detach(length) > 0.f && detach(l1) > 0.f && detach(l2) > 0.f)) return Vec3<T>(T(0.f));
    return n * (unit_angle(e1 / l1, e2 / l2) / length);
}

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
