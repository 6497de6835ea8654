// TriangleMesh: world-space transformation, validation of loaded data, smooth vertex normals and bounds.
#include "scene/mesh.h"

#include "core/error.h"
#include "scene/emitter.h"

#include <cmath>

namespace penumbra {

// Positions transform as points, normals with the inverse transpose and are renormalized (also for the
// identity, as Mitsuba 3 does); zero normals stay zero so that the shading falls back to the face normal.
void TriangleMesh::apply_transform(const Transform& to_world) {
    if (!to_world.is_identity())
        for (Vec3f& p : positions)
            p = to_world.apply_point(p);
    for (Vec3f& n : normals) {
        const Vec3f m = to_world.apply_normal(n);
        const float length = norm(m);
        n = length > 0.f ? m / length : m;
    }
}

void TriangleMesh::validate(const std::string& context) const {
    auto fail = [&](const std::string& what) { throw Error(context + ": " + what); };
    if (indices.size() % 3 != 0)
        fail("index count " + std::to_string(indices.size()) + " is not a multiple of 3");
    if (face_count() == 0) fail("mesh has no triangles");
    if (!normals.empty() && normals.size() != positions.size())
        fail(std::to_string(normals.size()) + " vertex normals for " + std::to_string(positions.size()) +
             " vertices");
    if (!uvs.empty() && uvs.size() != positions.size())
        fail(std::to_string(uvs.size()) + " texture coordinates for " + std::to_string(positions.size()) +
             " vertices");
    for (size_t i = 0; i < indices.size(); ++i)
        if (indices[i] >= positions.size())
            fail("triangle " + std::to_string(i / 3) + " references vertex " + std::to_string(indices[i]) +
                 " but the mesh has " + std::to_string(positions.size()) + " vertices");
    for (size_t i = 0; i < positions.size(); ++i)
        if (!is_finite(positions[i])) fail("vertex " + std::to_string(i) + " has a non-finite position");
    for (size_t i = 0; i < normals.size(); ++i)
        if (!is_finite(normals[i])) fail("vertex " + std::to_string(i) + " has a non-finite normal");
    for (size_t i = 0; i < uvs.size(); ++i)
        if (!std::isfinite(uvs[i].x) || !std::isfinite(uvs[i].y))
            fail("vertex " + std::to_string(i) + " has non-finite texture coordinates");
    for (const MeshAttribute& a : attributes) {
        const size_t count = a.name.rfind("face_", 0) == 0 ? face_count() : vertex_count();
        if (a.dim < 1 || a.values.size() != count * size_t(a.dim))
            fail("attribute '" + a.name + "' has " + std::to_string(a.values.size()) + " values for " +
                 std::to_string(count) + " elements of dimension " + std::to_string(a.dim));
    }
}

const MeshAttribute* TriangleMesh::attribute(const std::string& name) const {
    for (const MeshAttribute& a : attributes)
        if (a.name == name) return &a;
    return nullptr;
}

// Vertex normals as the angle-weighted sum of incident face normals (Thuermer & Wuethrich 1998, as Mitsuba
// 3). Vertices touched only by degenerate faces keep a zero normal (shading then uses the face normal).
void recompute_vertex_normals(TriangleMesh& mesh) {
    mesh.normals.assign(mesh.vertex_count(), Vec3f(0.f));
    for (size_t f = 0; f < mesh.face_count(); ++f) {
        const uint32_t* i = &mesh.indices[3 * f];
        const Vec3f p[3] = {mesh.positions[i[0]], mesh.positions[i[1]], mesh.positions[i[2]]};
        for (int k = 0; k < 3; ++k) mesh.normals[i[k]] += corner_normal(p, k);
    }
    for (Vec3f& n : mesh.normals) {
        const float length = norm(n);
        if (length > 0.f) n /= length;
    }
}

BoundingSphere bounding_sphere(const TriangleMesh& mesh) {
    Vec3f lo(Infinity), hi(-Infinity);
    for (const Vec3f& p : mesh.positions)
        lo = min(lo, p), hi = max(hi, p);
    return {(lo + hi) * 0.5f, norm(hi - lo) * 0.5f};
}

} // namespace penumbra
