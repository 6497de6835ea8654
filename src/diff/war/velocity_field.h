// The continuous velocity field of warped-area reparameterization in material path space (paper 000 §3.2,
// §5.1): for a path vertex p_K on the reference surface B, given its neighbour p_{K+1} on the detector's side
// (the spatial point y = X(p_{K+1}, θ)), the boundary integral over the curves where X(p_K, θ) is on a
// visibility boundary seen from y is rewritten as the interior integral ∫_B ∇·(f̂_K v_K) dA (Eq. 34), with
//   v(p) = ṽ(p) / W(p),  ṽ(p) = ∫_B w(q; p) v_dis(q) dA(q),  W(p) = ∫_B w(q; p) dA(q)      (Eqs. 14, 41–43)
//   w(q; p) = 1 / (D(q, p)^α + B(q))                                                       (Eq. 15, NOTES)
//   D(q, p) = (1/σ) (1 − exp(−r² / σ)),  r = |q − p| / r0,  σ = σ0,  r0 = |x − y|          (Eqs. 16–17)
//   v_dis(q) = ∂θ X⁻¹(z, θ) with z = rayIntersect(y → x_O, M) for an occluder x_O of segment y–X(q),
//              and 0 where X(q) is visible from y                                         (§3.2.2 Step 1,
//              Fig. 9)
//   B(q) = 0 where X(q) is invisible from y; where it is visible, penumbra's boundary test at q seen from y
//          (diff/was/boundary_test_function.h, capped at 1), which vanishes at q's own open edges and silhouettes.
// The text extraction writes Eq. 16 with its exponent outside the bracket: D = [(1/σ)(1 − e^{−r²/σ})]^α would
// double-count α with the weight; the NOTES' third-party port reads D as above with the weight 1/(D^α + B).
// The paper's B (Eq. 18, Fig. 7) is 1 on the visible side and B_dist = min(|⟨ω, n⟩|, distance to an open
// boundary) at the occluder on the invisible side. Two departures, by measurement (docs/war.md):
//  - on the invisible side B = 0, so w = D^{−α} there. Any B that vanishes at the boundary like the distance
//    u to it (or its square) puts the invisible side's weight, for p at a distance ε < σ from the boundary,
//    in a sliver u < ε³/σ² next to it that Gaussian auxiliary points almost never reach: the self-normalized
//    field then falls short of v_dis at the boundary (on a synthetic half plane, N_q = 16: 0.67 of it, and
//    the flux ∫ ∇·v 0.88 of v_dis; with B = 0: 0.95), and the validation shadows came out 10–40% low. With B
//    = 0 the weight near p's nearest boundary point is a blob of size ε, and the field still equals v_dis at
//    the boundary (∫ D^{−3} over a half disc at p diverges);
//  - on the visible side B vanishes at q's own open edges and silhouettes (§3.2.1's C.1 and C.2: static in
//    material space, so v·n must vanish there, yet f̂ jumps across them, e.g. at an area light's edge).
// A thin shell (two surfaces closer than ~σ0 r0, one of them occluded) would weight its far side's velocity
// heavily: the limit of B = 0.
//
// Sampling q (Fig. 10, Eqs. 44–46): q′ ~ N(p, s² I) in the tangent plane of p (s = spread · r0), projected
// along n(p) onto every surface the normal line meets within reach · r0 of the plane; each projection q has
// the area density pdf(q′) |⟨n(p), n(q)⟩|. Algorithm 1 gives W, ∇W, ṽ and ∇·ṽ from the same samples and
// v = ṽ/W, ∇·v = ∇·ṽ/W − ⟨∇W, ṽ⟩/W² (Eqs. 47, 62; paper 004's warp_coefficients). The gradient ∇_p w is
// taken with q fixed (w depends on p through r and r0): the exact divergence of the estimated field for the
// sampled q. The paper's Algorithm 1 line 16 (∇w·v_dis + w ∇·v_dis) is the form for q = p + t with the
// offsets t held fixed; there ∇w includes ∇B and ∇·v_dis a delta where v_dis jumps, which point samples
// cannot see. Projections beyond reach · r0 are left out: their D is ≥ (1/σ)(1 − e^{−reach²/σ}), their weight
// below σ^α ≈ 2e-7 of a near sample's.
//
// The field lives in B's tangent plane at p (triangles are flat: no curvature term). Applied to a vertex, it
// moves the material point, p(θ) = p + (θ − θ0) v(p), and multiplies the integrand by 1 + (θ − θ0) ∇·v, so
// that the tape's derivative of f̂ is ∂θ f̂ + ⟨∇f̂, v⟩ + f̂ ∇·v = ∂θ f̂ + ∇·(f̂ v) (Eq. 39). A vertex at infinity
// (the environment seen along a direction) is warped on the sphere of directions with paper 004's field
// (diff/was/warp_field.h), the same construction on that domain.
#pragma once
#include "diff/auxiliary_rng.h"
#include "diff/material_form.h"
#include "diff/was/boundary_test_function.h"
#include "diff/was/warp_field.h"

#include <span>
#include <vector>

namespace penumbra {

struct WarFieldOptions {
    int aux_count = 64;     // N_q (Algorithm 1): by measurement (docs/war.md)
    float sigma = 0.006f;   // σ0 of the distance D (paper: 0.006)
    float exponent = 3.f;   // α (paper: 3)
    float spread = 0.012f;  // standard deviation of q′ in units of r0: 2 σ0 by measurement (docs/war.md)
    float reach = 0.25f;    // projections searched within reach · r0 of the tangent plane
    bool antithetic = true; // q′ in pairs point-reflected about p
    // The field on the sphere at a vertex at infinity (paper 004's, diff/was/warp_field.h): after a BSDF
    // sample or NEE, the paper's N' = 8; for the camera's escaped samples N' = 32 with the jackknife of the
    // ratio, by measurement (docs/war.md): at N' = 8 without it the escaped camera samples of Mitsuba's
    // translate_diffuse_rectangle_constant come out 40% low.
    WarpOptions directions;
    WarpOptions camera_directions{.weight = {}, .aux_count = 32, .sphere_jackknife = true};
};

// War's auxiliary streams, apart from was's for the same camera sample.
inline constexpr AuxiliarySalt WarSalt{0x5bd1e995ULL, 1};

// w(q; p) and its gradient in p (Eqs. 15–17).
struct WarWeight {
    double w = 0;
    Vec3f gradient; // ∂p w, not yet projected on the tangent plane
};
// q − p, p − y (so r0 = |p − y|) and B(q).
WarWeight war_weight(const Vec3f& q_minus_p, const Vec3f& p_minus_y, float boundary,
                     const WarFieldOptions& o);

// One auxiliary point q.
struct WarAuxiliary {
    Vec3f offset;    // q − p
    float pdf = 0.f; // area density of q (Eq. 46)
    float boundary = 1.f;
    Vec3<Var> velocity; // v_dis(q): value 0, tangent ∂θ X⁻¹(z, θ); constant where X(q) is visible
};

// v(p) and ∇·v(p) as tape values: value 0, tangents v (in the tangent plane of n) and ∇·v (Eqs. 47, 62).
struct WarEstimate {
    Vec3<Var> velocity;
    Var divergence;
};
WarEstimate estimate_war_field(const Vec3f& n, const Vec3f& p_minus_y, std::span<const WarAuxiliary> aux,
                               const WarFieldOptions& o);

// What the field of one scene shares.
struct WarScene {
    const Scene& scene;
    const Parameters& params;
    const MaterialForm& form;
    const BoundaryTest& boundary;
    WarFieldOptions options;
};

// The neighbour p_{K+1} the field is conditioned on: its reference point (to spawn rays; n = 0 at a camera)
// and its material motion y(θ) = X(p_{K+1}, θ) (without its own warp: p_{K+1} is held fixed). At the camera
// the film's edge is not a boundary of the field: where it cuts the filters, diff/war/war.h adds the flux across
// it.
struct WarNeighbor {
    Interaction3f reference;
    Vec3<Var> position;
};

// Algorithm 1 lines 5–12 at the surface vertex `hit`: the auxiliary points with their boundary test and
// discontinuous velocity. `rays` counts the rays traced.
std::vector<WarAuxiliary> sample_war_auxiliary(const WarScene& s, const SurfaceInteraction3f& hit,
                                               const WarNeighbor& y, AuxiliaryRng& rng, uint64_t& rays);

// X(p + (θ − θ0) v, θ): the vertex at the displaced material point (barycentrics moved by v on the tape).
SurfaceInteraction<Var> displaced_vertex(const Parameters& params, const SurfaceInteraction3f& hit,
                                         const Vec3<Var>& velocity);

// A warped surface vertex: the interaction at the displaced point, J(p)·(1 + ∇·v) (value 1 at θ0), and the
// unwarped material point X(p, θ) (the neighbour of the next vertex's field).
struct WarVertex {
    SurfaceInteraction<Var> si;
    Var jacobian;
    Vec3<Var> material;
};
WarVertex war_vertex(const WarScene& s, const SurfaceInteraction3f& hit, const WarNeighbor& y,
                     AuxiliaryRng& rng, uint64_t& rays);

// The escaped direction ω from the surface vertex x (reference `x`, material motion `position`) warped on the
// sphere: value ω, tangent V(ω), and 1 + ∇·V.
WarpEstimate war_direction(const WarScene& s, const WarpOptions& field, const Interaction3f& x,
                           const Vec3<Var>& position, const Vec3f& omega, AuxiliaryRng& rng, uint64_t& rays);

} // namespace penumbra
