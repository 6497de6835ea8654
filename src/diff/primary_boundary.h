// The primary boundary term: the last path segment x_N -> camera is a boundary segment (paper 001 §4.3,
// Fig. 5-b). With the interior term in material form, the occluder's own material domain is fixed and only the
// background's is cut by the silhouette; in image space the term for pixel j is
//     ∫_silhouettes P_j(s) (−L_bg(s)) ((u_edge(s) − u_bg(s)) · n(s)) dℓ(s),
// with u the image-space velocities of the edge point and of the background point seen next to it, n the
// image-space normal pointing from the occluder to the background, and L_bg the radiance seen on the
// background side. Silhouette edges are sampled uniformly by projected length.
#pragma once
#include "core/image.h"
#include "diff/boundary_driver.h"
#include "diff/boundary_segment.h"

#include <memory>

namespace penumbra {

class PrimaryBoundary final : public BoundaryTerm {
public:
    // Selects, among the scene's discontinuity edges, the silhouettes seen from the reference camera.
    PrimaryBoundary(const Scene& scene, const SceneEdges& edges);
    ~PrimaryBoundary() override;
    Image derivative(const Parameters& params, const BoundaryOptions& options) const override;
    void gradient(const Parameters& params, const Image& adjoint, const BoundaryOptions& options,
                  std::vector<double>& gradient) const override;

    struct Silhouettes; // the prepared edges (defined in the .cpp)

private:
    const Scene& scene_;
    std::unique_ptr<const Silhouettes> silhouettes_;
};

} // namespace penumbra
