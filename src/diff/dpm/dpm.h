// Differentiable photon mapping (paper 003): derivatives of the SPPM image at a fixed merging radius, from
// photon-mapping paths on extended path space manifolds (diff/dpm/photon_path.h).
//
// Each pass traces the SPPM eye subpath of every pixel to its visible point (render/visible_point.h, the same
// random numbers as the `sppm` integrator) and photon_count light subpaths (render/photon_tracing.h); a
// fraction of the pixels (paper §6: 1/16; by default all) then samples photons merged at its visible point
// (paper: one; by default 16), with probability proportional to their luminance contribution, re-traces each
// photon's light subpath and differentiates the path's contribution (Eq. 23) on its EPSM:
//   DPM-C (§5.2.1)  the fixed-eye-ray EPSM: contribution derivatives only, comparable with central finite
//                   differences of SPPM renders at a fixed radius (`alpha` 1) with common random numbers;
//   DPM-G (§5.2.2)  the average of the fixed-density and vertex-merging EPSMs, whose eye rays move: their
//                   contribution derivatives, and the paths' screen-space motion (Eq. 7) for matching losses.
// The estimate is d/dθ of the photon-mapped light; emission seen directly or through specular chains and
// visibility discontinuities (boundary terms) are not differentiated. The radius is the scene's `sppm`
// integrator's initial_radius (automatic for 0), its photon_count, kernel, max_depth and rr_depth are used
// (without an `sppm` integrator: its defaults with the smooth kernel).
#pragma once
#include "core/sinkhorn.h"
#include "diff/parameters.h"
#include "diff/result.h"

namespace penumbra {

enum class DpmVariant { C, G };

struct DpmOptions {
    DpmVariant variant = DpmVariant::C;
    int spp = 16;    // SPPM passes (per batch)
    int batches = 1; // forward mode: independent batches of passes
    uint64_t seed = 0;
    int threads = 0;
    // Pixels that differentiate paths in each pass, and paths per such pixel: every pixel and 16 paths by
    // measurement (variance × time 0.006–0.009 of the paper's 1/16 of the pixels with one path each on the
    // Fig. 6 scene at 32² and 128², docs/dpm.md: a pass's photons are shared by all its paths).
    double pixel_fraction = 1.0;
    int paths = 16;
    // The matching loss's optimal transport: GeomLoss's schedule (blur 0.01, ε-scaling 0.5, stop after the
    // annealing), as the paper ran it; a 64² gradient took 1.1 s against 4.3 s at scaling 0.9 (two runs on a
    // loaded machine, indicative: docs/dpm.md).
    SinkhornOptions matching{0.01, 0.5, 1.0, 1e-3, 1};
    // The matching loss's gradient jackknifed over two halves of the passes (diff/dpm/matching_loss.h): at
    // the egg demo's solution it removes most of the bias of the noisy image's matching (docs/dpm.md), for
    // three debiased matchings instead of one.
    bool matching_jackknife = true;
    std::function<void(float)> progress;
};

// Forward mode along params.direction(), with the primal (SPPM at the fixed radius, same samples). DPM-C:
// dI/dθ, one term "photon-mapping". DPM-G: the contribution derivatives, each at the pixel its path was
// sampled in (term "contribution"), and the terms "screen_x" and "screen_y": the screen-space motion of the
// paths' contributions, Σ I dp/dθ per pixel (p in pixels, Eq. 7), with standard errors; with the
// contribution, d/dθ of any statistic of where the light lands (e.g. a caustic's centroid). DPM-C's eye rays
// do not move. The standard error of the image's mean comes from the spread of the batches' means
// (mean_stderr): photons are shared by neighbouring pixels, so pixel errors are correlated and sqrt(Σσ²)/N
// underestimates it (by up to 2× on the validation scenes, docs/dpm-validation.md). Warnings: the scene's
// sppm settings the estimate does not follow.
DerivativeImage dpm_derivative(const Scene& scene, const Parameters& params, const DpmOptions& options);
// Reverse mode: dL/dθ = Σ_pixels ∂L/∂I · dI/dθ for every enabled parameter (DPM-G: contribution derivatives).
Gradient dpm_gradient(const Scene& scene, const Parameters& params, const Image& adjoint,
                      const DpmOptions& options);

// The matching loss of §5.3 (Eq. 25, diff/dpm/matching_loss.h): the estimator's SPPM image is matched pixel
// to pixel to the target by entropic optimal transport on RGB + xy (Xing et al. 2022, 2023), and each pixel
// is pulled toward its match's position and colour; dL/dθ chains ∂L/∂p and ∂L/∂I with the screen-space motion
// and the contribution derivatives of the paths sampled in the pixel (DPM-G: averaged over its two EPSMs;
// DPM-C: contribution only). The passes are traced twice, with independent random numbers: once for the image
// to match (in two halves for the jackknife, `matching_jackknife`), once to differentiate. The gradient's
// loss is Eq. 25 averaged over the pixels, of the whole image.
Gradient dpm_matching_gradient(const Scene& scene, const Parameters& params, const Image& target,
                               const DpmOptions& options);

} // namespace penumbra
