// Harmonic weights of warped-area sampling (paper 004 Eq. 8): w(ω, ω') = 1 / (D(ω, ω') + B(ω'))^γ with the
// vMF distance D(ω, ω') = e^{κ(1 − ⟨ω, ω'⟩)} − 1, and their gradient in ω on the sphere (Eq. 12 needs ∂ω w).
// The paper writes γ = 1; the authors' code (redner, experimental) defaults to γ = 2 and Mitsuba 3's reparam
// to 3 (NOTES-public-implementations.md). Any γ ≥ 1 makes w blow up at a boundary (B = 0) as ω' → ω, which is
// what pulls the field to the boundary's velocity.
#pragma once
#include "core/vector.h"

#include <cmath>

namespace penumbra {

struct HarmonicWeight {
    float kappa = 1e4f;   // concentration of the distance D (the auxiliary vMF's κ)
    float exponent = 3.f; // γ

    struct Value {
        double w;       // w(ω, ω')
        Vec3f gradient; // ∂ω w, tangent to the sphere at ω
    };

    // Eq. 8 and its ω-gradient: ∂ω w = γ κ e^{κ(1−c)} (D + B)^{−γ−1} (ω' − c ω), c = ⟨ω, ω'⟩ = 1 −
    // one_minus_cos.
    Value operator()(const Vec3f& omega, const Vec3f& omega_aux, float one_minus_cos, float boundary) const {
        const double x = double(kappa) * double(one_minus_cos);
        if (x > 600.0) return {0.0, Vec3f(0.f)}; // e^{−γx}: below every other weight
        const double d = std::expm1(x) + double(boundary);
        const double base = std::fmax(d, 1e-300);
        const double w = std::pow(base, -double(exponent));
        const double dw = double(exponent) * double(kappa) * std::exp(x) * w / base;
        const Vec3f tangent = omega_aux - omega * (1.f - one_minus_cos);
        return {w, tangent * float(dw)};
    }
};

} // namespace penumbra
