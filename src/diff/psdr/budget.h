// The sample budget of the psdr estimator from one number. `--spp N` buys what giving every term N samples per
// pixel would cost (Mitsuba's convention for its projective integrators: sppc = sppp = sppi = spp), and spends
// it where it reduces the error most: a calibration pass (1/16 of the budget, discarded) measures each term's
// variance V_k and cost c_k per sample per pixel, and the term gets s_k ∝ √(V_k / c_k) samples per pixel, the
// allocation that minimizes Σ_k V_k / s_k at a fixed total cost Σ_k c_k s_k (Neyman allocation). Costs are
// counted in rays and AD tape nodes (diff/sample_cost.h), not seconds, so the split, and the image, are the
// same for a seed whatever the machine or thread count.
//   forward mode: V_k = Σ over pixels and channels of the per-sample variance of the derivative image;
//   reverse mode: V_k = Σ over parameters of the per-sample variance of the gradient for the given adjoint.
// With a static camera the calibration also picks the first vertex's parameterization (image space or material
// form, diff/first_vertex.h) whose optimal split has the lower variance × cost, unless `base` fixes it.
#pragma once
#include "diff/psdr/psdr.h"

#include <string>

namespace penumbra {

// Per-term sample counts (per batch, base.interior.batches batches) for a total of `spp` samples per pixel, the
// rest of the options (seed, threads, path settings, first vertex) taken from `base`.
PsdrOptions psdr_budget(const Scene& scene, const Parameters& params, const PsdrOptions& base, int spp);
// The same for reverse mode with the adjoint image ∂L/∂I (one batch).
PsdrOptions psdr_gradient_budget(const Scene& scene, const Parameters& params, const Image& adjoint,
                                 const PsdrOptions& base, int spp);

// "interior 12, primary 1500, direct 0, indirect 0, pixel 0 spp, image-space first vertex" (totals over the
// batches).
std::string describe_budget(const PsdrOptions& options);

} // namespace penumbra
