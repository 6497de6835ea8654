// linearcurve: Mitsuba 3's piecewise-linear round curves, tessellated.
//
//  parameter                   type       default
//  filename                    string     (required) control points "x y z radius" per line, a blank line
//                                         between curves, at least 2 points per curve
//  to_world                    transform  identity: applied to the positions, not to the radii (as Mitsuba)
//  silhouette_sampling_weight  float      1 (Mitsuba's weight for its silhouette sampling; penumbra samples
//                                         silhouette edges by length and accepts it without effect)
//  (bsdf, media: as every shape; an area emitter is refused, see below)
//
// Each segment is the tube swept by a sphere whose radius varies linearly: the frustum tangent to the end
// spheres (curve_tube.h), with a sphere at every control point for Mitsuba's spherical joints and end caps.
// uv = (u around the segment's axis from Mitsuba's u_rad, v = (segment + t) / segment count over all
// curves of the file). The joint spheres overlap the tubes; hidden inner surfaces never show, but they would
// count in the emitting area, so the curve cannot carry an area emitter.
#include "scene/shapes/curve_tube.h"
#include "scene/shapes/shapes.h"

namespace penumbra {

TriangleMesh make_linearcurve(const Properties& props, const LoadContext& ctx) {
    const auto curves = load_curves(props, ctx, 2);
    props.get_float("silhouette_sampling_weight", 1.f);
    size_t segments = 0;
    for (const auto& curve : curves)
        segments += curve.size() - 1;
    TriangleMesh m;
    size_t g = 0; // global segment index
    for (const auto& curve : curves) {
        for (size_t i = 0; i < curve.size(); ++i, ++g) {
            const ControlPoint& a = curve[i];
            const ControlPoint& b = curve[i + 1 < curve.size() ? i + 1 : i];
            const float v = float(g) / float(segments);
            const Vec3f axis = i + 1 < curve.size() ? b.p - a.p : a.p - curve[i - 1].p;
            if (a.radius > 0.f && norm(axis) > 0.f) append_sphere(m, a.p, a.radius, axis, v);
            if (i + 1 == curve.size()) break; // g then counts the next curve's first segment
            const Vec3f dc = b.p - a.p;
            const float dr = b.radius - a.radius;
            if (!(norm(dc) > std::abs(dr))) continue; // one end sphere contains the other: no tube
            const uint32_t r0 = append_ring(m, a.p, dc, a.radius, dr, v);
            const uint32_t r1 = append_ring(m, b.p, dc, b.radius, dr, float(g + 1) / float(segments));
            connect_rings(m, r0, r1);
        }
    }
    return m;
}

} // namespace penumbra
