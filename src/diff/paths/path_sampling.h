// Path sampling methods for differentiable rendering (paper 002, Su & Gkioulekas 2024) for parameters that
// do not move geometry (BSDF, texture and emitter values): differential vertex sampling with MIS over the
// location of the differential vertex (§4.1, Eqs. 19-24), next-event estimation (Appendix B), path replay
// backpropagation (Algorithm 1) and adaptive pixel sampling (§4.2, Algorithm 2).
//
// Three entry points, all built on the same per-path estimator (diff/paths/path_replay.h):
//   path_sampling_derivative     forward mode: dI/dθ along params.direction(), per pixel, with batches and
//                                per-pixel standard errors (adaptive: pixel counts from a given adjoint);
//   path_sampling_gradient       reverse mode given an adjoint image ∂L/∂I: passes 2 and 3 of PRB;
//   path_sampling_loss_gradient  the three passes: a primal image (pass 1, its own samples) gives the loss
//                                and its adjoint, then passes 2 and 3 (optionally with adaptive pixels).
// Variants (benchmark axes): options.differential (differential vs. BSDF sampling) × options.nee ×
// options.adaptive. Same seed ⇒ same result for any thread count.
//
// Which parameter drives the differential density at a vertex: the BSDF decides (BSDF::has_differential_lobe;
// a rough conductor: its isotropic α; a blend: its weight, else its first child with a lobe). The estimator
// is unbiased for every enabled parameter whatever the density: p_∂f only changes which paths are drawn, and
// the MIS mixture density is a true density of the drawn paths. Limits: geometric parameters (motions,
// vertex_positions) are rejected (use the interior / psdr estimators); at a vertex where a channel of f
// vanishes but not its derivative (e.g. a reflectance of exactly 0), PRB's division by f loses that channel's
// contribution.
#pragma once
#include "core/image_loss.h"
#include "diff/parameters.h"
#include "diff/paths/path_replay.h"
#include "diff/result.h"

#include <functional>

namespace penumbra {

struct PathSamplingOptions {
    int spp = 16;                 // samples per pixel per batch (mean over the film with adaptive sampling);
                                  // loss gradient: the total of all three passes
    int batches = 1;              // independent batches (standard errors)
    uint64_t seed = 0;
    int threads = 0;              // 0 = all
    PathSettings path;            // depth limits and Russian roulette (path_settings(scene))
    bool differential = true;     // differential vertex sampling (false: BSDF sampling)
    float q = 0.5f;               // probability of making a vertex the differential vertex (paper: 0.5)
    bool nee = true;              // next-event estimation with the MIS weights of Appendix B
    bool adaptive = false;        // adaptive pixel sampling by |∂L/∂I|
    double defensive = 0.05;      // uniform share ε of the adaptive pixel density (diff/paths/adaptive_pixels.h)
    double primal_fraction = 0.75; // loss gradient: share of spp spent on pass 1 (paper: primal:adjoint 3:1)
    std::function<void(float)> progress;
};

// Throws Error unless every enabled parameter is a non-geometric value and the options are valid.
void check_path_sampling(const Scene& scene, const Parameters& params, const PathSamplingOptions& options);

// `adjoint` is only read with options.adaptive (pixel counts ∝ |adjoint|, the paper's importance).
DerivativeImage path_sampling_derivative(const Scene& scene, const Parameters& params, const PathSamplingOptions& options,
                                         const Image& adjoint = Image());
// Values are the means over the batches (each batch's in batch_values), the primal pass 2's image (with
// adaptive pixels: the same 1 / c_j weighting).
Gradient path_sampling_gradient(const Scene& scene, const Parameters& params, const Image& adjoint,
                                const PathSamplingOptions& options);
// The loss is the mean of pass 1's over the batches, the primal pass 1's image of the last batch.
Gradient path_sampling_loss_gradient(const Scene& scene, const Parameters& params, const Image& target,
                                     LossKind loss, const PathSamplingOptions& options);

} // namespace penumbra
