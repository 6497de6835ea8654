// Adaptive pixel sampling (paper 002 §4.2, Algorithm 2): pixels are importance-sampled by the adjoint
// radiance, P_j ∝ Σ_channels |∂L/∂I_j|, mixed with a small defensive uniform share ε so that every pixel keeps
// a positive probability (and the per-pixel derivative image stays unbiased):
//   P_j = (1 − ε) |a_j| / Σ|a| + ε / N_pixels.
// A budget of M = N_pixels · spp paths is spread as expected counts c_j = M P_j; pixel j draws
// n_j = ⌊c_j⌋ + Bernoulli(c_j − ⌊c_j⌋) paths (randomized rounding: E[n_j] = c_j, less variance than M
// independent draws) and each path is weighted by 1 / c_j — the division by the selection probability that
// makes Σ_j a_j (1/c_j) Σ_{k<=n_j} g_k an unbiased estimate of Σ_j a_j ∂I_j/∂θ. (The public implementation
// averaged over the drawn samples instead, which is biased.) Uniform sampling is the case c_j = spp.
#pragma once
#include "core/image.h"

#include <cstdint>
#include <vector>

namespace penumbra {

struct PixelBudget {
    int width = 0, height = 0;
    std::vector<double> expected; // c_j, the expected number of paths of pixel j

    // n_j for this seed: deterministic per (seed, pixel).
    int count(uint64_t seed, uint64_t pixel) const;
};

PixelBudget uniform_budget(int width, int height, double spp);
// Throws Error if the adjoint is zero everywhere while ε = 0, or on a negative / non-finite input.
PixelBudget adaptive_budget(const Image& adjoint, double spp, double defensive);

} // namespace penumbra
