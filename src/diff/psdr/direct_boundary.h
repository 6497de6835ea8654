// The direct boundary term: next-event segments x_D -> y (toward a point on an emitter) that graze an edge
// (paper 001 §4.2–4.3; for point lights the segment x_src x_0 is the boundary segment). In the receiver's
// material frame the lit region is cut by the shadow curve; for pixel j the term is
//     ∫_lights ∫_shadow curve  W_j(x_D) f_s(camera ← x_D → y) G'(x_D, y) L_e(y) (v(x_D) · n_shadow) dℓ(x_D) dA(y)
// with W_j the camera importance (filter at the projection times |ds/dA|), v the velocity of the shadow
// curve relative to the receiver's material motion and n_shadow its normal pointing into the shadow. It is
// sampled from edge points x_B (uniform by length) and emitter samples y, extending y -> x_B to the receiver,
// with dℓ(x_D) = |dx_D/dx_B| dℓ(x_B) along the edge (diff/psdr/boundary_segment.h). In participating media the
// segment carries its transmittance and may end at a medium vertex on the shadow sheet behind the edge
// (σ_s, the phase function toward the camera, no cosine; diff/psdr/boundary_segment.h gives the sheet's measure).
#pragma once
#include "diff/boundary_driver.h"
#include "diff/psdr/boundary_segment.h"


namespace penumbra {

// One boundary sample whose source endpoint is an emitter sample, with the detector subpath's camera
// connections at depths t_min..t_max (diff/psdr/detector_subpath.h): the direct term uses t = 0 only, the
// indirect term t ≥ 1.
// In media the segment leaves the light in the emitter's medium (render/light_medium.h).
BoundarySample sample_emitter_boundary(const Scene& scene, const SceneEdges& edges, const SegmentContext& context,
                                       int t_min, int t_max, const PathSettings& settings,
                                       const BoundarySampleIndex& index, Sampler& sampler, RayCounter& rays);

class DirectBoundary final : public BoundaryTerm {
public:
    // `edges` (the scene's discontinuity edges) must outlive the estimator.
    DirectBoundary(const Scene& scene, const SceneEdges& edges) : scene_(scene), edges_(edges) {}
    Image derivative(const Parameters& params, const BoundaryOptions& options) const override;
    void gradient(const Parameters& params, const Image& adjoint, const BoundaryOptions& options,
                  std::vector<double>& gradient) const override;

private:
    const Scene& scene_;
    const SceneEdges& edges_;
};

} // namespace penumbra
