// The pixel-boundary term of the material-form camera vertex (paper 001 §4.3): with a box reconstruction
// filter, P_j(s) jumps at pixel j's edges, and as the geometry (or the camera) moves, the material points
// seen just inside an edge cross it. For pixel j the term is
//     −∮_{∂pixel j} L(s) (ṡ(s) · n_out(s)) dℓ(s),
// with ṡ the film-space velocity of the material point seen at s (first order, on the tape) and n_out the
// pixel's outward normal; the interior term, whose filter is constant inside the pixel, misses it. Continuous
// filters (tent, gaussian) jump only where the film cuts them (hdrfilm without sample_border:
// Film::filter_weight): the term then runs over the film's edge alone. The image-space first vertex needs
// none (its filter does not move; diff/first_vertex.h). Points are stratified along every pixel edge, with
// the same offsets and random numbers on a pixel's opposite edges; each interior edge point contributes to
// the two pixels it separates. In participating media the material point seen at s is where a free flight along
// the camera ray ends (diff/media_radiance.h): a medium vertex, moving by the volume motion, or a surface.
// Warped-area sampling (diff/was/warped_area.h) takes the same term with the warp field V(s) in place of ṡ: the
// divergence theorem on the film leaves −∮ L (V · n_out) over the edges where the filter (or the film) ends.
#pragma once
#include "core/image.h"
#include "diff/boundary_driver.h"

#include <functional>

namespace penumbra {

// Whether the pixel-boundary term is needed: a box filter, or a filter cut at the film's edge, and a
// material-form first vertex.
bool needs_pixel_boundary(const Scene& scene, const Parameters& params, FirstVertex first_vertex);

// The film-space velocity across the edge at s (`across`: the edge's unit normal, +x or +y) for edge sample
// `sample`, as a tape value (value ~0): what replaces the material point's ṡ · across.
using FilmEdgeVelocity =
    std::function<Var(const Vec2f& s, const Vec2f& across, uint64_t sample, RayCounter& rays)>;

class PixelBoundary final : public BoundaryTerm {
public:
    // `strata`: samples per unit edge segment (0: from the options' samples_per_pixel).
    explicit PixelBoundary(const Scene& scene, FilmEdgeVelocity velocity = {}, int strata = 0)
        : scene_(scene), velocity_(std::move(velocity)), strata_(strata) {}
    // Both are zero (and cost nothing) unless needs_pixel_boundary().
    Image derivative(const Parameters& params, const BoundaryOptions& options) const override;
    void gradient(const Parameters& params, const Image& adjoint, const BoundaryOptions& options,
                  std::vector<double>& gradient) const override;

private:
    const Scene& scene_;
    FilmEdgeVelocity velocity_;
    int strata_;
};

} // namespace penumbra
