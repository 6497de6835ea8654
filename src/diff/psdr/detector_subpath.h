// The detector subpath of a boundary path (paper 001 Eq. 33; Algorithm 1, line 17): from the receiver x_D0
// of a boundary segment, an importance-transport random walk connected to the pinhole camera at every vertex
// (as in light tracing). The connection at depth t (t = 0: x_D0 itself) splats at the vertex's film
// position with weight
//     Π_{k<t} f_k |cos| / p_k  ·  f_t(x_{t-1} → x_t → camera) · |ds/dA(x_t)| / |cos θ_t|,
// that is, the camera's importance in film measure times the subpath's throughput; the boundary segment's own
// factors (the incident term and the cosine at x_D0 toward the source) are the caller's.
//
// Through participating media the walk is volumetric (as light tracing): free flights between vertices (their
// weights Tr σ_s / p or Tr / P(pass) in the throughput), medium vertices with the phase function in place of
// f |cos| (phase sampling has weight 1), and every camera connection carries its transmittance; at a medium
// vertex the importance is |ds/dA⊥| (the camera's importance per unit area orthogonal to the connection).
#pragma once
#include "diff/psdr/boundary_segment.h"
#include "render/path_tracer.h"

#include <array>

namespace penumbra {

struct CameraConnection {
    Vec2f s;        // film position (pixels)
    Color3f weight;
    int t;          // depth of the connected vertex
    Var velocity;   // the segment's normal velocity relative to the receiver's flow along this subpath
};

struct DetectorConnections {
    static constexpr int Capacity = 8;
    std::array<CameraConnection, Capacity> items;
    int count = 0;
};

// Connections of the vertices at depths t_min ≤ t ≤ t_max (t_max < 0: unbounded, with Russian roulette
// from settings.rr_depth; at most Capacity connections), starting at the segment's x_D0 (a surface receiver
// or a medium vertex). The connection of x_D0 itself also requires the camera to see the segment's
// `dark_point`, just across the discontinuity: where the discontinuity is also a silhouette seen by the
// camera (a light at the camera, say), the jump is counted once, by the primary term, instead of twice. A
// contact segment's x_D0 is never connected directly: seen by the camera, the contact is the primary term's
// (a silhouette resting on the surface).
//
// Each connection carries the segment's velocity relative to the receiver's flow along its subpath: x_D0 as
// the camera sees it (t = 0), its material point, or, where x_D0 lies within the contact length of the next
// vertex toward the camera or is reached through its delta lobe, the flow of the chain of surface vertices
// back to the camera (MaterialForm's contact flow, the delta lobes' directions: as the interior's path walk).
void detector_connections(const Scene& scene, const MaterialForm& form, const BoundarySegment& segment, int t_min,
                          int t_max, const PathSettings& settings, Sampler& sampler, RayCounter& rays,
                          DetectorConnections& out);

} // namespace penumbra
