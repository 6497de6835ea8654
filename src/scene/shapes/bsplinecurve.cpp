// bsplinecurve: Mitsuba 3's uniform cubic B-spline round curves, tessellated.
//
//  parameter                   type       default
//  filename                    string     (required) control points "x y z radius" per line, a blank line
//                                         between curves, at least 4 points per curve
//  to_world                    transform  identity: applied to the positions, not to the radii (as Mitsuba)
//  silhouette_sampling_weight  float      1 (Mitsuba's weight for its silhouette sampling; penumbra samples
//                                         silhouette edges by length and accepts it without effect)
//  (bsdf, emitter, media: as every shape)
//
// A curve of n control points has n - 3 segments, segment j blending points j..j+3 with the uniform cubic
// B-spline basis; position and radius are both splines. The tube swept by the sphere of varying radius is
// tessellated with BSplineSteps rings per segment (curve_tube.h); like Mitsuba's, it is open-ended (no end
// caps). uv = (u around the centerline from Mitsuba's u_rad, v = (segment + t) / segment count over all
// curves of the file).
#include "scene/shapes/curve_tube.h"
#include "scene/shapes/shapes.h"

namespace penumbra {
namespace {

constexpr int BSplineSteps = 16;

// Uniform cubic B-spline basis at t in [0, 1] and its derivative (weights of points j..j+3).
void bspline_basis(float t, float w[4], float dw[4]) {
    const float t2 = t * t, t3 = t2 * t;
    w[0] = (1.f - 3.f * t + 3.f * t2 - t3) / 6.f;
    w[1] = (4.f - 6.f * t2 + 3.f * t3) / 6.f;
    w[2] = (1.f + 3.f * t + 3.f * t2 - 3.f * t3) / 6.f;
    w[3] = t3 / 6.f;
    dw[0] = (-3.f + 6.f * t - 3.f * t2) / 6.f;
    dw[1] = (-12.f * t + 9.f * t2) / 6.f;
    dw[2] = (3.f + 6.f * t - 9.f * t2) / 6.f;
    dw[3] = 3.f * t2 / 6.f;
}

} // namespace

TriangleMesh make_bsplinecurve(const Properties& props, const LoadContext& ctx) {
    const auto curves = load_curves(props, ctx, 4);
    props.get_float("silhouette_sampling_weight", 1.f);
    size_t segments = 0;
    for (const auto& curve : curves)
        segments += curve.size() - 3;
    TriangleMesh m;
    size_t g = 0; // global segment index
    for (const auto& curve : curves) {
        uint32_t previous = 0;
        for (size_t j = 0; j + 3 < curve.size(); ++j, ++g)
            for (int s = j == 0 ? 0 : 1; s <= BSplineSteps; ++s) {
                const float t = float(s) / float(BSplineSteps);
                float w[4], dw[4];
                bspline_basis(t, w, dw);
                Vec3f c(0.f), dc(0.f);
                float r = 0.f, dr = 0.f;
                for (int k = 0; k < 4; ++k) {
                    c += curve[j + k].p * w[k];
                    dc += curve[j + k].p * dw[k];
                    r += curve[j + k].radius * w[k];
                    dr += curve[j + k].radius * dw[k];
                }
                const uint32_t ring = append_ring(m, c, dc, r, dr, (float(g) + t) / float(segments));
                if (s > 0) connect_rings(m, previous, ring);
                previous = ring;
            }
    }
    return m;
}

} // namespace penumbra
