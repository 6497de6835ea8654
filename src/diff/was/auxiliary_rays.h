// Auxiliary rays of warped-area sampling at one path vertex (paper 004 Algorithm 2 lines 3–8): each auxiliary
// direction ω' is traced from the vertex x, the boundary test is evaluated at its hit, and its direct warp
// V_direct(ω') = ∂θ ω' (Eq. 6) is put on the tape: the hit's material point moves with the geometry,
// y(θ) = X(p, θ), and ω'(θ) = (y(θ) − x(θ)) / |y(θ) − x(θ)|, whose derivative is ∂θ y / |∂ω y| projected on
// the sphere, i.e. Eq. 6 with the moving vertex x included.
#pragma once
#include "diff/material_form.h"
#include "diff/was/boundary_test_function.h"
#include "diff/was/warp_field.h"

namespace penumbra {

// The differentiable vertex x: its reference point (for spawning rays) and its position on the tape.
struct WarpVertex {
    Interaction3f reference; // p and geometric normal n at θ0 (n = 0 in a medium or at a camera)
    Vec3<Var> position;      // x(θ); constant when the vertex does not move
};

// The point an auxiliary ray's hit follows as θ moves, for its direct warp: the material point X(p, θ), or next
// to an implicit edge inside its triangle the edge's own moving point (edge_following_point, implicit_edges.h).
Vec3<Var> auxiliary_point(const MaterialForm& form, const BoundaryTest& boundary, const SurfaceInteraction3f& hit,
                          const Vec3f& origin, const Vec3f& direction);

// Traces one auxiliary direction (Algorithm 2 lines 4–8); `scale` is the boundary test's distance scale
// (diff/was/boundary_test_function.h; κ in the estimators, 0 for the paper's vertex rule).
AuxiliarySample trace_auxiliary(const Scene& scene, const MaterialForm& form, const BoundaryTest& boundary,
                                const WarpVertex& x, const VmfSample& s, float scale = 0.f);

// Algorithm 2 / 3 at x for the direction ω: samples the auxiliary directions, traces them and estimates the
// warp field and its divergence.
template <typename Rng>
WarpEstimate estimate_warp_at(const Scene& scene, const MaterialForm& form, const BoundaryTest& boundary,
                              const WarpVertex& x, const Vec3f& omega, const WarpOptions& o, Rng& rng) {
    std::vector<AuxiliarySample> aux;
    for (const VmfSample& s : sample_auxiliary(omega, o, rng))
        aux.push_back(trace_auxiliary(scene, form, boundary, x, s, o.weight.kappa));
    return estimate_warp(omega, aux, o);
}

// The point where the warped ray x(θ) + t ω(θ) meets the moving triangle of `hit` (Möller–Trumbore on the
// tape, as MaterialForm::ray_vertex for a fixed ray): the next path vertex as a function of the warped
// direction, so that the radiance it carries has the derivative ∂θ L + ⟨∂ω L, V⟩ (Algorithm 1 line 4).
SurfaceInteraction<Var> warped_vertex(const Parameters& params, const SurfaceInteraction3f& hit,
                                      const Vec3<Var>& origin, const Vec3<Var>& direction);

} // namespace penumbra
