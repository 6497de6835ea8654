// The primary boundary term: the last path segment x_1 -> camera is a boundary segment (paper 001 §4.3,
// Fig. 5-b). For pixel j it integrates, along the image of the edges where the radiance seen through the film
// jumps, the jump times the discontinuity's image-space normal velocity:
//   image-space first vertex (diff/first_vertex.h): the camera rays are fixed, and the image jumps at
//     silhouettes and at creases of face-normal meshes:  ∫ P_j(s) (L_a(s) − L_b(s)) (u_edge(s) · n(s)) dℓ(s);
//   material-form first vertex: the occluder's own material domain is fixed and only the background's is cut
//     by the silhouette:  ∫ P_j(s) (−L_bg(s)) ((u_edge(s) − u_bg(s)) · n(s)) dℓ(s),
// with u the image-space velocities of the edge point and of the background's material point seen next to it,
// n the image-space normal pointing from side a (the occluder) to side b (the background), and L the radiance
// seen on either side. Edges are sampled by the length of their image within the film.
//
// Through participating media the camera segment carries its transmittance to the edge (common to both sides),
// and the far side of a silhouette is what a free flight from the edge's depth on meets: a medium vertex (the
// primary shadow sheet behind the edge; in material form its point moves by the volume motion) or the
// background surface; the in-scattering in front of the edge is the same on both sides and is left out.
#pragma once
#include "core/image.h"
#include "diff/boundary_driver.h"
#include "diff/psdr/boundary_segment.h"

#include <memory>

namespace penumbra {

class PrimaryBoundary final : public BoundaryTerm {
public:
    // `edges` (the scene's discontinuity edges) must outlive the estimator; the ones seen by the camera are
    // selected per call (which depends on the first vertex's parameterization).
    PrimaryBoundary(const Scene& scene, const SceneEdges& edges);
    ~PrimaryBoundary() override;
    Image derivative(const Parameters& params, const BoundaryOptions& options) const override;
    void gradient(const Parameters& params, const Image& adjoint, const BoundaryOptions& options,
                  std::vector<double>& gradient) const override;

    struct Silhouettes; // the prepared edges (defined in the .cpp)

private:
    const Scene& scene_;
    const SceneEdges& edges_;
};

} // namespace penumbra
