// The warp field of warped-area sampling at one path vertex (paper 004 §3.3–4.1): for a direction ω sampled
// by the path tracer, V(ω) = ∫ w(ω, ω') V_direct(ω') dω' / ∫ w(ω, ω') dω' (Eq. 7) with harmonic weights w
// (Eq. 8) and the direct warp V_direct(ω') = ∂θ ω' of auxiliary rays ω' ~ vMF(ω, κ) (Eq. 6), and its
// divergence ∇·V (Eq. 12), from the same auxiliary samples. The boundary derivative of ∫ L(ω, θ) dω is then
// ∫ ∇·(L V) = ∫ ⟨∂ω L, V⟩ + L ∇·V (Eq. 5): with the estimate below, the path tracer evaluates its
// contribution L at the warped direction and multiplies it by the divergence Jacobian, and the tape's
// derivative of L(ω_warped(θ), θ) · J(θ) is ∂θ L + ⟨∂ω L, V⟩ + L ∇·V (Algorithm 1, lines 6–7).
//
// The field is tangent to the sphere: V is projected on the tangent plane at ω, and the divergence is the
// surface divergence ∇_S·(P V) = tr(P ∂ω V) − 2 ⟨ω, V⟩ (the last term, absent from the paper's planar Eq. 12,
// is the sphere's curvature; it vanishes as κ → ∞).
#pragma once
#include "core/var.h"
#include "core/vmf.h"
#include "diff/was/harmonic_weight.h"

#include <span>
#include <vector>

namespace penumbra {

// Options of the estimator. Defaults: κ = 1e4 and N' = 8 (paper §5.1), antithetic on and Russian roulette
// with p = 0.4 over batches of 4 (the authors' code, NOTES-public-implementations.md), cap 512 (paper §5.5).
// The unbiased estimator is heavy-tailed: its differences F_k − F_{k−1} shrink only as 1/k while their
// weights 1/P(N ≥ k) grow geometrically, so its variance is bounded only by the cap. Measured on the moving
// occluder (κ = 1e3): per-sample variance ~2e4 at p = 0.4 (batch 4) or p = 1/8 (batch 1, the paper's), ~500
// at p = 0.05 (batch 4, 10× the rays), against ~90 for the consistent N' = 8.
struct WarpOptions {
    HarmonicWeight weight;  // κ of the vMF auxiliary distribution and of D; exponent γ
    int aux_count = 8;      // N' of the consistent estimator (Algorithm 2)
    bool antithetic = true; // auxiliary samples in point-reflected pairs about ω (§4.2)
    bool unbiased = false;  // Russian-roulette debiasing of the normalization (Algorithm 3)
    float rr_stop = 0.4f;   // unbiased: probability to stop after each batch, N_batches ~ Geom(rr_stop)
    int rr_batch = 4;       // unbiased: samples per batch (the telescoping sum runs over prefixes of batches)
    int rr_cap = 512; // unbiased: at most this many samples (the paper's cap; truncation bias beyond it)
    bool film_jackknife = true; // consistent, on the film: the delete-a-group jackknife of the ratio
    bool sphere_jackknife = false; // consistent, on the sphere: the same jackknife (war's escaped directions)
};

// One auxiliary ray: its direction and density, the boundary test at its hit and its direct warp.
struct AuxiliarySample {
    VmfSample vmf;
    float boundary = 1.f; // B(ω') (Appendix A)
    Vec3<Var> warp; // value ω', tangent ∂θ ω' = V_direct(ω') (Eq. 6); constant when its hit does not move
};

// The estimate at ω, as tape values whose derivatives carry the field.
struct WarpEstimate {
    Vec3<Var> direction; // value ω, derivative V(ω) (Eq. 7, tangent at ω)
    Var jacobian;        // value 1, derivative ∇·V(ω) (Eq. 12)
};

// The number of auxiliary samples (Algorithm 2: N'; Algorithm 3 line 2: a Geom(rr_stop) number of batches of
// rr_batch samples, capped at rr_cap).
template <typename Rng> int auxiliary_count(const WarpOptions& o, Rng& rng) {
    if (!o.unbiased) return o.aux_count;
    const int max_batches = std::max(1, o.rr_cap / o.rr_batch);
    int batches = 1;
    while (batches < max_batches && rng.next_1d() >= o.rr_stop)
        ++batches;
    return batches * o.rr_batch;
}

// The auxiliary directions at ω (Algorithm 2 line 3, Algorithm 3 lines 2–4), in antithetic pairs when
// enabled. `Rng` has next_1d() and next_2d() (Sampler).
template <typename Rng>
std::vector<VmfSample> sample_auxiliary(const Vec3f& omega, const WarpOptions& o, Rng& rng) {
    const int count = auxiliary_count(o, rng);
    const Frame3f frame(omega);
    std::vector<VmfSample> samples;
    samples.reserve(size_t(count));
    while (int(samples.size()) < count) {
        samples.push_back(sample_vmf(frame, o.weight.kappa, rng.next_2d()));
        if (o.antithetic && int(samples.size()) < count) samples.push_back(antithetic(frame, samples.back()));
    }
    return samples;
}

// Per-sample coefficients of an estimate from weights w_i and gradients ∂w_i (both already divided by the
// auxiliary density; Algorithm 2 lines 6–7): V = Σ field_i V_i and ∇·V = Σ ⟨divergence_i, V_i⟩. Algorithm 2
// (consistent, self-normalized: lines 10–13), or when o.unbiased Algorithm 3 as a telescoping sum over batch
// prefixes, F = Σ_k λ_k F_k with F_k Algorithm 2 on the first k batches and λ_k = 1/P(N ≥ k) − 1/P(N ≥ k+1)
// (λ_N = 1/P(N ≥ N)), so that E[F] = lim F_k. Both are exact for a uniform field (Σ divergence_i = 0).
struct WarpCoefficients {
    std::vector<double> field;
    std::vector<Vec3f> divergence;
};
WarpCoefficients warp_coefficients(std::span<const double> w, std::span<const Vec3f> grad_w,
                                   const WarpOptions& o);
// The delete-a-group jackknife of Algorithm 2's ratio (groups of `group` consecutive samples: antithetic pairs
// stay together), G F_N − (G − 1)/G Σ_k F_(−k): removes the ratio's O(1/N) bias, still linear in the V_i.
WarpCoefficients jackknife_coefficients(std::span<const double> w, std::span<const Vec3f> grad_w, size_t group);

// V(ω) and ∇·V(ω) on the sphere from the auxiliary samples (the coefficients above, with P(ω) and the
// curvature term −2⟨ω, V⟩).
WarpEstimate estimate_warp(const Vec3f& omega, std::span<const AuxiliarySample> aux, const WarpOptions& o);

// The primary vertex: the domain is the film (pixel units), the auxiliary positions are x' ~ N(x, σ² I) with
// σ = 1/√κ' chosen by the caller (the film's Gaussian filter's scale, or smaller), and the direct warp is the
// film motion ∂θ x' of the point seen through x' (Eq. 6 with the camera's projection in place of ∂ω y).
struct PixelAuxiliarySample {
    Vec2f offset;         // x' − x
    float pdf = 0.f;      // N(0, σ² I) density of the offset
    float boundary = 1.f; // B at the point seen through x'
    Vec2<Var> warp;       // value x', derivative ∂θ x'
};
struct PixelWarpEstimate {
    Vec2<Var> position; // value x, derivative V(x)
    Var jacobian;       // value 1, derivative ∇·V(x)
};

// Offsets x' − x ~ N(0, σ² I) (Box–Muller), the antithetic partner being −(x' − x); boundary and warp are
// left for the caller to fill by tracing the camera rays through x + offset.
template <typename Rng>
std::vector<PixelAuxiliarySample> sample_pixel_auxiliary(float sigma, const WarpOptions& o, Rng& rng) {
    const int count = auxiliary_count(o, rng);
    std::vector<PixelAuxiliarySample> samples;
    samples.reserve(size_t(count));
    while (int(samples.size()) < count) {
        const Vec2f u = rng.next_2d();
        const float r = sigma * std::sqrt(-2.f * std::log1p(-u.x)), phi = 2.f * Pi * u.y;
        PixelAuxiliarySample s;
        s.offset = Vec2f(r * std::cos(phi), r * std::sin(phi));
        s.pdf = std::exp(-0.5f * (r * r) / (sigma * sigma)) / (2.f * Pi * sigma * sigma);
        samples.push_back(s);
        if (o.antithetic && int(samples.size()) < count) {
            s.offset = Vec2f(-s.offset.x, -s.offset.y);
            samples.push_back(s);
        }
    }
    return samples;
}

// V(x) and ∇·V(x) on the film (Eq. 7 and 12 with the planar distance D(x, x') = e^{|x' − x|²/(2σ²)} − 1).
PixelWarpEstimate estimate_pixel_warp(const Vec2f& x, std::span<const PixelAuxiliarySample> aux, float sigma,
                                      const WarpOptions& o);

} // namespace penumbra
