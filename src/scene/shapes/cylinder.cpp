// cylinder: Mitsuba 3's open tube (no end caps), tessellated.
//
//  parameter  type   default
//  p0         point  (0, 0, 0)  object-space start of the centerline
//  p1         point  (0, 0, 1)  object-space end of the centerline
//  radius     float  1
//  (to_world, flip_normals, bsdf, emitter, media: as every shape, see shape_factory.cpp)
//
// Mitsuba's parameterization: with d = p1 - p0 and the frame (s, t, d/|d|) of coordinate_system(d/|d|),
// x(u, v) = p0 + r cos(2 pi u) s + r sin(2 pi u) t + v d, uv = (u, v), outward normal (x - axis) / r. The
// tessellation has CylinderSegments quads around the axis (vertices on the exact surface, analytic vertex
// normals, the seam column duplicated at u = 0 and u = 1): its silhouette width is within
// 1 - cos(pi / 128) = 3e-4 and its area within 1e-4 (relative) of the cylinder's. Mitsuba keeps a to_world
// with a non-uniform scale out of the circle (with a warning); here the tube is transformed as any mesh.
#include "scene/shapes/shapes.h"

#include "core/frame.h"

#include <cmath>

namespace penumbra {
namespace {

constexpr int CylinderSegments = 128;

} // namespace

TriangleMesh make_cylinder(const Properties& props) {
    const float radius = props.get_float("radius", 1.f);
    if (!(radius > 0.f) || !std::isfinite(radius)) props.raise("radius", "must be positive");
    const Vec3f p0 = props.get_vector("p0", Vec3f(0.f)), p1 = props.get_vector("p1", Vec3f(0.f, 0.f, 1.f));
    const Vec3f d = p1 - p0;
    if (!(norm(d) > 0.f) || !is_finite(d))
        props.raise("p1", "must differ from p0 (the axis has zero length)");
    const Frame<float> frame(d / norm(d));

    TriangleMesh m;
    for (int i = 0; i <= CylinderSegments; ++i) {
        // The seam vertices (u = 1) repeat the first ones exactly (cos(2 pi) is not 1 in float), so that the
        // seam's edges are merged as interior edges rather than taken for boundary (always silhouette) edges.
        const float u = float(i) / float(CylinderSegments), phi = i == CylinderSegments ? 0.f : 2.f * Pi * u;
        const Vec3f n = frame.s * std::cos(phi) + frame.t * std::sin(phi);
        for (int j = 0; j <= 1; ++j) {
            m.positions.push_back(p0 + n * radius + d * float(j));
            m.normals.push_back(n);
            m.uvs.emplace_back(u, float(j));
        }
    }
    // Each triangle steps in u, then in v: cross(dx/du, dx/dv) points outward.
    for (uint32_t i = 0; i < uint32_t(CylinderSegments); ++i) {
        const uint32_t a = 2 * i, b = 2 * (i + 1);
        m.indices.insert(m.indices.end(), {a, b, b + 1, a, b + 1, a + 1});
    }
    return m;
}

} // namespace penumbra
