// What the derivative estimators return: a derivative image (forward mode) or a gradient (reverse mode).
#pragma once
#include "core/image.h"
#include "diff/sample_cost.h"

#include <string>
#include <vector>

namespace penumbra {

struct DerivativeImage {
    Image primal;      // the image estimated from the same samples (detached values)
    Image derivative;  // dI/dθ
    Image stderr_img;  // per-pixel standard error of `derivative` (empty with a single batch)
    double seconds = 0;
    SampleCost cost;
};

struct Gradient {
    std::vector<double> values; // dL/dθ, one per enabled parameter scalar
    std::vector<std::string> warnings; // terms the estimate leaves out (shown to the user)
    Image primal;
    double seconds = 0;
    SampleCost cost;
};

} // namespace penumbra
