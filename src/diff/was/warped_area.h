// Warped-area sampling (paper 004, Algorithm 1): the total derivative of the image, interior and boundary
// together, from an ordinary path tracer. Every integral along a path is written over directions (solid angle
// at surface vertices, the film at the camera) and differentiated as
//   ∂θ ∫ f dω = ∫ ∂θ f + ∇·(f V) dω  (Eq. 5)
// with a warp field V that is continuous and equals the velocity of the discontinuities of f at them (Eq. 7,
// estimated from auxiliary rays: diff/was/warp_field.h, diff/was/auxiliary_rays.h). A sampled direction ω becomes
// ω(θ) = ω + (θ − θ0) V(ω) and the contribution is multiplied by the divergence Jacobian 1 + (θ − θ0) ∇·V, so
// the tape's derivative of the path contribution is the estimator of Eq. 5 at every vertex at once.
//   camera    the film position x is sampled from a defensive mixture of the reconstruction filter and the
//             uniform density on its support (diff/film_sample.h: the filter's score ∂x k / k is unbounded
//             where a truncated filter falls to zero, the mixture's ∂x k / p is not); the auxiliary positions
//             are N(x, σ² I) on the film with σ the filter's standard deviation (§3.3); the filter's gradient
//             term is controlled by the linear control variate of Appendix D (forward mode); where the
//             filters jump (a box filter's pixel edges; the film's edge without sample_border) the field does
//             not vanish, and the divergence theorem on the film leaves −∮ P_j L (V · n_out) over those
//             edges: the pixel-edge term (diff/pixel_boundary.h with V in place of the material velocity);
//   surfaces  the BSDF-sampled direction and the emitter-sampled direction (NEE) are warped with vMF
//             auxiliary rays (κ, N'); the next vertex is where the warped ray meets the moving triangle;
//   delta     specular vertices and delta lights are not warped (no integral to warp): shadows of point,
//             spot and directional lights are discontinuities that no boundary test at the previous vertex
//             sees, and their motion is missed (paper 004 uses area and vMF lights).
// Surfaces only (no participating media).
#pragma once
#include "diff/parameters.h"
#include "diff/pixel_options.h"
#include "diff/result.h"
#include "diff/was/warp_field.h"

namespace penumbra {

struct WasOptions : PixelOptions {
    // κ, N', antithetic, unbiased (diff/was/warp_field.h). κ = 1e4 (the paper's); N' = 32 by measurement (the
    // paper's 8 leaves the consistent estimator biased by 15–50% of the boundary derivative on the validation
    // scenes, docs/warped-area-sampling.md).
    WarpOptions warp = [] {
        WarpOptions o;
        o.aux_count = 32;
        return o;
    }();
    bool control_variate = true; // Appendix D at the camera vertex (forward mode)
};

// Throws a clear Error for what the method cannot differentiate (media, sensors without one center of
// projection).
void require_was_support(const Scene& scene, const Parameters& params);

// Forward mode: dI/dθ along params.direction() (with per-pixel standard errors over the batches).
DerivativeImage was_derivative(const Scene& scene, const Parameters& params, const WasOptions& options);
// Reverse mode: dL/dθ = Σ_pixels adjoint · dI/dθ for every enabled parameter scalar (no control variate).
Gradient was_gradient(const Scene& scene, const Parameters& params, const Image& adjoint,
                      const WasOptions& options);

} // namespace penumbra
