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
#include "diff/harmonic_weight.h"

#include <span>
#include <vector>

namespace penumbra {

// Options of the estimator. Defaults: κ = 1e4 and N' = 8 (paper §5.1), antithetic on and Russian roulette
// with p = 0.4 over batches of 4 (the authors' code, NOTES-public-implementations.md), cap 512 (paper §5.5).
struct WarpOptions {
    HarmonicWeight weight;  // κ of the vMF auxiliary distribution and of D; exponent γ
    int aux_count = 8;      // N' of the consistent estimator (Algorithm 2)
    bool antithetic = true; // auxiliary samples in point-reflected pairs about ω (§4.2)
    bool unbiased = false;  // Russian-roulette debiasing of the normalization (Algorithm 3)
    float rr_stop = 0.4f;   // unbiased: probability to stop after each batch, N_batches ~ Geom(rr_stop)
    int rr_batch = 4;       // unbiased: samples per batch (the telescoping sum runs over prefixes of batches)
    int rr_cap = 512; // unbiased: at most this many samples (the paper's cap; truncation bias beyond it)
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

// The auxiliary directions at ω (Algorithm 2 line 3, Algorithm 3 lines 2–4): N' samples (antithetic pairs
// when enabled), or for the unbiased estimator a Geom(rr_stop) number of batches of rr_batch samples, capped.
// `Rng` has next_1d() and next_2d() (Sampler).
template <typename Rng>
std::vector<VmfSample> sample_auxiliary(const Vec3f& omega, const WarpOptions& o, Rng& rng) {
    int count = o.aux_count;
    if (o.unbiased) {
        const int max_batches = std::max(1, o.rr_cap / o.rr_batch);
        int batches = 1;
        while (batches < max_batches && rng.next_1d() >= o.rr_stop)
            ++batches;
        count = batches * o.rr_batch;
    }
    const Frame3f frame(omega);
    std::vector<VmfSample> samples;
    samples.reserve(size_t(count));
    while (int(samples.size()) < count) {
        samples.push_back(sample_vmf(frame, o.weight.kappa, rng.next_2d()));
        if (o.antithetic && int(samples.size()) < count) samples.push_back(antithetic(frame, samples.back()));
    }
    return samples;
}

// V(ω) and ∇·V(ω) from the auxiliary samples: Algorithm 2 (consistent, self-normalized: lines 10–13), or when
// o.unbiased Algorithm 3 as a telescoping sum over batch prefixes, F = Σ_k λ_k F_k with F_k Algorithm 2 on
// the first k batches and λ_k = 1/P(N ≥ k) − 1/P(N ≥ k+1) (λ_N = 1/P(N ≥ N)), so E[F] = lim F_k.
WarpEstimate estimate_warp(const Vec3f& omega, std::span<const AuxiliarySample> aux, const WarpOptions& o);

} // namespace penumbra
