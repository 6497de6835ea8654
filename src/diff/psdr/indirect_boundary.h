// The indirect boundary term (paper 001 §5.2, Algorithm 1, Eqs. 40–43): boundary segments x_S0 → x_D0 that are
// neither the camera segment (diff/psdr/primary_boundary.h) nor an emitter's segment seen directly by the camera
// (diff/psdr/direct_boundary.h). Two techniques, each with the full budget:
//  - emitter sources: an emitter sample and an edge point, with the detector subpath's camera connections
//    at depths t ≥ 1 (e.g. a shadow seen in a glossy reflection; the only way to reach point lights);
//  - multi-directional sampling: an edge point x_B and a direction ω_B (uniform over the directions grazing the
//    edge), the endpoints drawn by sampleInteraction behind (x_S0) and beyond (x_D0) the edge — the first
//    surfaces, or in participating media medium vertices where free flights end — the Jacobian of Eqs. 40–43
//        dA(x_S0) dℓ(x_D0) / (dℓ(x_B) dσ(ω_B)) = r_S² / |cos φ_S| · dℓ(x_D0)/dℓ(x_B)   (two surfaces; no cosine
//        at a medium vertex, whose measure is the volume, and the sheet's dA(x_D0) = dℓ(x_B) dr_D (r_D/r_S) sin φ_B),
//    the radiance x_S0 sends toward x_D0 (the source subpath, by path tracing with next-event estimation, or
//    volumetric path tracing in media; its emission is the emitter technique's) and the detector subpath's
//    camera connections at all depths.
// Path lengths respect the scene's max_depth.
#pragma once
#include "diff/boundary_driver.h"
#include "diff/psdr/boundary_segment.h"
#include "diff/psdr/edge_tree.h"

#include <optional>

namespace penumbra {

class IndirectBoundary final : public BoundaryTerm {
public:
    // `edges` (the scene's discontinuity edges) must outlive the estimator.
  IndirectBoundary(const Scene& scene, const SceneEdges& edges);
  Image derivative(const Parameters& params, const BoundaryOptions& options) const override;
  void gradient(const Parameters& params, const Image& adjoint, const BoundaryOptions& options,
                std::vector<double>& gradient) const override;

private:
    const Scene& scene_;
    const SceneEdges& edges_;
    std::optional<EdgeTree> camera_edges_; // the camera technique's edge tree, where the technique applies
};

} // namespace penumbra
