// The detector subpath of a boundary path (paper 001 Eq. 33; Algorithm 1, line 17): from the receiver x_D0
// of a boundary segment, an importance-transport random walk connected to the pinhole camera at every vertex
// (as in light tracing). The connection at depth t (t = 0: x_D0 itself) splats at the vertex's film
// position with weight
//     Π_{k<t} f_k |cos| / p_k  ·  f_t(x_{t-1} → x_t → camera) · |ds/dA(x_t)| / |cos θ_t|,
// that is, the camera's importance in film measure times the subpath's throughput; the boundary segment's own
// factors (the incident term and the cosine at x_D0 toward the source) are the caller's.
#pragma once
#include "render/path_tracer.h"

#include <array>

namespace penumbra {

struct CameraConnection {
    Vec2f s;        // film position (pixels)
    Color3f weight;
    int t;          // depth of the connected vertex
};

struct DetectorConnections {
    static constexpr int Capacity = 8;
    std::array<CameraConnection, Capacity> items;
    int count = 0;
};

// Connections of the vertices at depths t_min ≤ t ≤ t_max (t_max < 0: unbounded, with Russian roulette
// from settings.rr_depth; at most Capacity connections). `x_d0.wi` points toward the source. The connection
// of x_D0 itself also requires the camera to see `dark_point`, the receiver just across the discontinuity
// curve: where the curve is also a silhouette seen by the camera (a light at the camera, say), the jump is
// counted once, by the primary term, instead of twice.
void detector_connections(const Scene& scene, const SurfaceInteraction3f& x_d0, const Vec3f& dark_point, int t_min,
                          int t_max, const PathSettings& settings, Sampler& sampler, RayCounter& rays,
                          DetectorConnections& out);

} // namespace penumbra
