// What every derivative estimator returns, and the front of diff/method.h with it: a derivative image
// (forward mode) or a gradient (reverse mode), each with the one line that describes how it was estimated,
// what the estimate leaves out (warnings, for the user) and the deterministic count of the work
// (diff/sample_cost.h).
#pragma once
#include "core/error.h"
#include "core/image.h"
#include "diff/sample_cost.h"
#include <array>

#include <limits>
#include <string>
#include <vector>

namespace penumbra {

// One term of a derivative (psdr: interior, primary, direct, indirect, pixel; a one-term method: the whole).
struct DerivativeTerm {
    std::string name;
    Image derivative;
    Image stderr_img; // empty with a single batch
    SampleCost cost;
    double seconds = 0;
    double mean_stderr = 0; // of the image's mean, from the batches' means (DerivativeImage::mean_stderr)
    std::array<Image, 2> block_stderr{}; // of its 2 × 2 and 4 × 4 block means (DerivativeImage::block_stderr)
};

struct DerivativeImage {
    Image derivative; // dI/dθ along params.direction()
    Image stderr_img; // per-pixel standard error of `derivative` (empty with a single batch)
    Image primal;     // the image estimated from the same samples (detached values; may be empty)
    std::vector<DerivativeTerm>
        terms; // the method's terms separately (`penumbra derivative --terms`), or none
    // The standard error of the image's mean (over pixels and channels) from the spread of the batches'
    // means: pixel errors correlate (a sample splats over the filter's pixels, a path carries all three
    // channels, photons are shared), so sqrt(Σσ²)/N understates it. 0 with a single batch.
    double mean_stderr = 0;
    // The standard errors of the 2 × 2 and 4 × 4 block means (ImageBatches::Blocks), from the batches' block
    // means for the same reason (empty with a single batch).
    std::array<Image, 2> block_stderr{};
    std::string description;           // one line for the log ("interior + boundary terms (...)")
    std::vector<std::string> warnings; // what the estimate leaves out, for the user
    double seconds = 0;
    SampleCost cost; // cost.dropped: the NaN policy's count (diff/method.h)

    // The term named `name`; throws Error if the method has none of that name.
    const DerivativeTerm& term(const std::string& name) const {
        for (const DerivativeTerm& t : terms)
            if (t.name == name) return t;
        throw Error("the derivative has no term '" + name + "'");
    }
};

struct Gradient {
    std::vector<double> values; // dL/dθ, one per enabled parameter scalar
    // paths: each batch's values (for statistics of combinations of the scalars); empty elsewhere.
    std::vector<std::vector<double>> batch_values;
    Image primal; // the image estimated on the way (may be empty)
    std::string description;
    std::vector<std::string> warnings;                      // what the estimate leaves out, for the user
    double loss = std::numeric_limits<double>::quiet_NaN(); // a loss gradient: the loss of its primal image
    double seconds = 0;
    SampleCost cost; // cost.dropped: the NaN policy's count (diff/method.h)
};

} // namespace penumbra
