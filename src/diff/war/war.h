// The unidirectional estimator of warped-area reparameterization in material path space (paper 000 §5.2.1,
// Algorithm 2): the reparameterized differential path integral (Eq. 38)
//   dI/dθ = ∫ ( d f̂(p̄)/dθ + Σ_{K=0}^{N−1} [∇·(f̂_K v_K)](p_K) ) dμ(p̄)
// estimated by path tracing with next-event estimation in material form (paper 001), with no boundary
// sampling. Path vertices are indexed from the light (x_0) to the camera (x_N); each vertex p_K but the
// camera's carries the field v_K of diff/war/velocity_field.h conditioned on its detector-side
// neighbour p_{K+1}:
//   p^D_1 (first hit)   on the camera's position (primary visibility);
//   p^D_{n+1}           on p^D_n (the vertex found by BSDF sampling, emitters included);
//   p^S_n (NEE)         on p^D_n (the light point of next-event estimation).
// A warped vertex is evaluated at p(θ) = p + (θ − θ0) v(p) with the factor 1 + (θ − θ0) ∇·v in its area
// Jacobian, so the tape's derivative of the path contribution is d f̂/dθ + Σ_K ∇·(f̂ v_K) = Eq. 48 × pdf.
// Eqs. 49–51 factor f̂ out of the divergence sum, Σ_K [∇ĝ_K/ĝ_K · v_K + ∇·v_K], and keep its prefix sum Σ^D_n
// along the detector subpath so that each NEE path costs O(1); on the tape that prefix sum is the tangent of
// the detector subpath's throughput: each vertex's warp is put on the tape once, when the vertex is sampled,
// and every NEE path through it reuses it (the throughput's tangent is Σ^D_n × throughput). Forward mode
// propagates the tangents once per path, reverse mode runs one adjoint pass per path: O(1) work per vertex
// and per connection, whatever the path length. diff/war/velocity_field.h's war_vertex serves any path
// sampler (a bidirectional one warps the source subpath's vertices conditioned on their detector-side
// neighbour too).
//
// Not covered: delta lights (no integral to warp at the light: the motion of point, spot and directional
// lights' shadows is missed, as in paper 004) and vertices after a delta BSDF lobe (no area integral there).
// The environment seen directly is a vertex at infinity warped on the sphere, conditioned on the camera.
// Surfaces only. Where the pixel filters jump (a box filter's pixel edges, any filter at the film's edge
// without sample_border) the first vertex's field does not vanish, and the flux −∮ P_j L (ṡ · n_out) across
// those static film edges is added (diff/pixel_boundary.h), with ṡ the film velocity of the reparameterized
// first vertex (or warped escaped direction) seen there.
#pragma once
#include "diff/pixel_driver.h"
#include "diff/result.h"
#include "diff/war/velocity_field.h"

namespace penumbra {

struct WarOptions : PixelOptions {
    WarFieldOptions field;
};

// Throws a clear Error for what the estimator cannot differentiate (media, sensors without one center of
// projection).
void require_war_support(const Scene& scene, const Parameters& params);

// One camera sample of pixel (x, y) with its auxiliary stream: war's and war-bdpt's per-sample functions.
using WarSample = std::function<Color3<Var>(Sampler&, AuxiliaryRng&, int x, int y, RayCounter& rays)>;
// The loop's samples (`sample` with the auxiliary stream of each camera sample), war's film-edge term (the
// flux of the reparameterized first vertex across the edges where the filters jump, diff/pixel_boundary.h,
// per batch seed) and the warning naming `method` for point and spot lights' shadows. `sample` and `field`
// keep what they use alive as long as the loop.
void set_war_samples(PixelLoop& loop, std::shared_ptr<const WarScene> field, WarSample sample,
                     const std::string& method);

// War's or war-bdpt's loop: what the estimator shares across samples (`Context`, with the field as `field`),
// made once, and `camera_sample` on every camera sample.
template <typename Context>
PixelLoop
war_loop(const Scene& scene, const Parameters& params, const WarOptions& options, const std::string& method,
         Color3<Var> (*camera_sample)(const Context&, Sampler&, AuxiliaryRng&, int, int, RayCounter&)) {
    PixelLoop loop(scene, params, options);
    const auto c = std::make_shared<const Context>(scene, params, options);
    set_war_samples(
        loop, {c, &c->field},
        [c, camera_sample](Sampler& sampler, AuxiliaryRng& rng, int x, int y, RayCounter& rays) {
            return camera_sample(*c, sampler, rng, x, y, rays);
        },
        method);
    return loop;
}

// Forward mode: dI/dθ along params.direction() (with per-pixel standard errors over the batches).
DerivativeImage war_derivative(const Scene& scene, const Parameters& params, const WarOptions& options);
// Reverse mode: dL/dθ = Σ_pixels adjoint · dI/dθ for every enabled parameter scalar.
Gradient war_gradient(const Scene& scene, const Parameters& params, const Image& adjoint,
                      const WarOptions& options);

} // namespace penumbra
