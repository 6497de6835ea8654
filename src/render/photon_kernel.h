// Density-estimation kernels of photon mapping, as functions of the relative distance t = d / r ∈ [0, 1]
// between a photon and the density-estimation point. Both are normalized over the disc of radius r:
// ∫_disc K(|x| / r) / (π r²) dA = 1, so that the estimate is Σ_p K(t_p) Φ_p f_p / (π r²) whatever the kernel.
// Templated on the scalar type so that the differentiable photon-mapping estimators evaluate the same code.
#pragma once
#include "scene/integrator_settings.h"

namespace penumbra {

// 1 (constant) or smooth_scale (1 - 6t⁵ + 15t⁴ - 10t³) (smooth) for t < 1, else 0: the kernels below with
// their normalization.
template <typename T> T scaled_photon_kernel(PhotonKernel kernel, const T& t, float smooth_scale) {
    if (!(t < T(1))) return T(0);
    if (kernel == PhotonKernel::Constant) return T(1);
    const T t3 = t * t * t;
    return T(smooth_scale) * (T(1) - t3 * (T(10) - t * (T(15) - T(6) * t)));
}

// Eq. (22) of paper 003 (Hachisuka et al. 2010): K(t) = 3.5 (1 - 6t⁵ + 15t⁴ - 10t³) for t < 1, else 0;
// ∫₀¹ (1 - 6t⁵ + 15t⁴ - 10t³) 2πt dt = 2π/7, hence the factor 3.5. The constant kernel is K(t) = 1 for t < 1.
template <typename T> T photon_kernel(PhotonKernel kernel, const T& t) { return scaled_photon_kernel(kernel, t, 3.5f); }

// The same kernels normalized over the ball of radius r, for volume photons: ∫_ball K(|x| / r) / (4/3 π r³) dV
// = 1. ∫₀¹ (1 - 6t⁵ + 15t⁴ - 10t³) 4πt² dt = 4π · 5/84, hence the factor 84/15 = 5.6.
template <typename T> T volume_photon_kernel(PhotonKernel kernel, const T& t) {
    return scaled_photon_kernel(kernel, t, 5.6f);
}

} // namespace penumbra
