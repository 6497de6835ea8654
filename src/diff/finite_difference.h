// Reference derivatives by central finite differences with common random numbers, and the comparison metric
// used everywhere in penumbra: relerr = Σ|D − R| / Σ|R| plus z-scores against standard errors.
#pragma once
#include "core/image.h"
#include "diff/parameters.h"
#include "render/render.h"
#include <array>

namespace penumbra {

struct FiniteDifference {
    Image derivative;  // (I(θ0 + h) − I(θ0 − h)) / 2h along the enabled direction
    Image stderr_img;  // per-pixel standard error from independent batches (empty with one batch)
    double seconds = 0;
    double mean_stderr = 0; // of the image's mean, from the batches' means (0 with one batch, or stored)
    std::array<Image, 2>
        block_stderr{}; // of the 2 × 2 and 4 × 4 block means, from the batches (empty: stored)
};

// Renders with the scene's integrator at θ0 ± h·direction (same seeds on both sides, film positions stratified
// within each pixel) in `batches` independent batches, and restores θ0 afterwards.
FiniteDifference finite_difference(Scene& scene, Parameters& params, double h, const RenderOptions& options,
                                   int batches = 1);

struct Comparison {
    double relerr = 0;            // Σ|D − R| / Σ|R| over pixels and channels
    double mean_test = 0, mean_ref = 0;
    double mean_z = 0;            // (mean_test − mean_ref) / stderr of the difference of means (0 without stderr)
    double outlier_fraction = 0;  // fraction of pixel channels with |D − R| > 3 σ (0 without stderr)
    double noise_relerr = 0;      // relerr expected from noise alone, sqrt(2/π) Σσ / Σ|R| (0 without stderr)
};

// `test_stderr` / `ref_stderr` are optional (empty images); standard errors combine in quadrature. The
// standard error of an image mean is estimated as sqrt(Σσ²)/N (pixels independent).
Comparison compare_images(const Image& test, const Image& ref, const Image& test_stderr = Image(),
                          const Image& ref_stderr = Image());

} // namespace penumbra
