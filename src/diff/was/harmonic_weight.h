// Harmonic weights of warped-area sampling (paper 004 Eq. 8): w(ω, ω') = 1 / (D(ω, ω') + B(ω'))^γ with the
// vMF distance D(ω, ω') = e^{κ(1 − ⟨ω, ω'⟩)} − 1, and their gradient in ω on the sphere (Eq. 12 needs ∂ω w).
// At the primary vertex the same weights live on the film: D(x, x') = e^{|x' − x|² / (2σ²)} − 1.
//
// The exponent: the paper writes γ = 1; the authors' code (redner, experimental) defaults to γ = 2 and
// Mitsuba 3's reparam to 3 (NOTES-public-implementations.md). We default to 3: near a boundary B vanishes
// linearly with the distance to it, and ∫ w dω' must diverge at boundary points for the field to take the
// boundary's velocity there (Eq. 8's limit). With D ~ κ r²/2 that integral is finite for γ = 1 (the field is
// then not valid), diverges only logarithmically for γ = 2 (slow convergence: on the moving occluder of
// tests/test_was_warp.cpp, κ = 1e3, the consistent estimate is −32% off at N' = 8 and −9% at N' = 64), and
// like 1/r for γ = 3 (−13% at N' = 8, −1% at N' = 32).
#pragma once
#include "core/vector.h"

#include <cmath>

namespace penumbra {

struct HarmonicWeight {
    float kappa = 1e4f;   // concentration of the distance D (the auxiliary vMF's κ)
    float exponent = 3.f; // γ

    struct Value {
        double w;       // w(ω, ω')
        Vec3f gradient; // ∂ω w, tangent to the sphere at ω (film: (∂x w, 0))
    };

    // Eq. 8 on the sphere: ∂ω w = γ κ e^{κ(1−c)} (D + B)^{−γ−1} (ω' − c ω), c = ⟨ω, ω'⟩ = 1 − one_minus_cos.
    Value operator()(const Vec3f& omega, const Vec3f& omega_aux, float one_minus_cos, float boundary) const {
        return evaluate(double(kappa) * double(one_minus_cos), boundary,
                        (omega_aux - omega * (1.f - one_minus_cos)) * kappa);
    }
    // Eq. 8 on the film, x' = x + offset: ∂x w = γ e^{|d|²/(2σ²)} (D + B)^{−γ−1} d / σ².
    Value planar(const Vec2f& offset, float sigma, float boundary) const {
        const float inv_var = 1.f / (sigma * sigma);
        return evaluate(0.5 * double(offset.x * offset.x + offset.y * offset.y) * inv_var, boundary,
                        Vec3f(offset.x, offset.y, 0.f) * inv_var);
    }

  private:
    // w = (e^x − 1 + B)^{−γ} and ∂w = γ e^x (D + B)^{−γ−1} (−∂x), given −∂x.
    Value evaluate(double x, float boundary, const Vec3f& minus_dx) const {
        if (x > 600.0) return {0.0, Vec3f(0.f)}; // e^{−γx}: below every other weight
        const double base = std::fmax(std::expm1(x) + double(boundary), 1e-300);
        const double w = std::pow(base, -double(exponent));
        return {w, minus_dx * float(double(exponent) * std::exp(x) * w / base)};
    }
};

} // namespace penumbra
