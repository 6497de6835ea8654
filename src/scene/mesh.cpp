// TriangleMesh: world-space transformation and validation of loaded data.
#include "scene/mesh.h"

#include "core/error.h"

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
}

} // namespace penumbra
