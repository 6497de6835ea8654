// The von Mises–Fisher distribution on the unit sphere, p(ω') = C(κ) exp(κ (⟨μ, ω'⟩ − 1)), the auxiliary-ray
// distribution of warped-area sampling (paper 004 §4.1). Stable for every κ: at κ → 0 it is uniform on the
// sphere, at κ = 1e6 the angular radius is ~1e-3 and 1 − cosθ is kept as its own quantity (cosθ in float
// would round it away).
#pragma once
#include "core/frame.h"
#include "core/math.h"

#include <cmath>

namespace penumbra {

// A sampled direction: in the world and in the local frame of the mean (local z = μ), with its density.
struct VmfSample {
    Vec3f direction;
    Vec3f local;
    float one_minus_cos; // 1 − ⟨μ, ω'⟩, exact even when cosθ rounds to 1
    float pdf;           // solid-angle density
};

// C(κ) = κ / (2π (1 − e^{−2κ})): the normalization with the density written as C exp(κ (cosθ − 1)); expm1
// keeps it exact at small κ, where it tends to 1/(4π).
inline double vmf_normalization(double kappa) {
    return kappa > 1e-8 ? kappa / (-2.0 * double(Pi) * std::expm1(-2.0 * kappa)) : 1.0 / (4.0 * double(Pi));
}

// p(ω') = C(κ) exp(−κ (1 − cosθ)), in terms of 1 − cosθ.
inline float vmf_pdf(float kappa, float one_minus_cos) {
    return float(vmf_normalization(kappa) * std::exp(-double(kappa) * double(one_minus_cos)));
}

// Inverse CDF of cosθ: cosθ = 1 + log(u + e^{−2κ}(1 − u)) / κ, written as 1 − cosθ = −log1p((1 − u)
// expm1(−2κ)) / κ so that neither small κ (where it tends to 2(1 − u), uniform) nor large κ loses digits.
inline double vmf_one_minus_cos(double kappa, double u) {
    if (kappa < 1e-8) return 2.0 * (1.0 - u);
    const double omc = -std::log1p((1.0 - u) * std::expm1(-2.0 * kappa)) / kappa;
    return std::fmin(2.0, std::fmax(0.0, omc));
}

// Samples ω' ~ vMF(μ, κ) with μ = frame.n.
inline VmfSample sample_vmf(const Frame3f& frame, float kappa, const Vec2f& u) {
    const double omc = vmf_one_minus_cos(kappa, u.x);
    const double cos_theta = 1.0 - omc, sin_theta = std::sqrt(std::fmax(0.0, omc * (2.0 - omc)));
    const double phi = 2.0 * double(Pi) * u.y;
    VmfSample s;
    s.local = Vec3f(float(sin_theta * std::cos(phi)), float(sin_theta * std::sin(phi)), float(cos_theta));
    s.direction = normalize(frame.to_world(s.local));
    s.one_minus_cos = float(omc);
    s.pdf = vmf_pdf(kappa, float(omc));
    return s;
}

// The antithetic partner of a sample: its point reflection about the mean (local x and y negated), with the
// same density (§4.2: "rotate our samples 180° about the center of the distribution").
inline VmfSample antithetic(const Frame3f& frame, const VmfSample& s) {
    VmfSample r = s;
    r.local = Vec3f(-s.local.x, -s.local.y, s.local.z);
    r.direction = normalize(frame.to_world(r.local));
    return r;
}

} // namespace penumbra
