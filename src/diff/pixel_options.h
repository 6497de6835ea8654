// The options of every estimator that integrates the image derivative over camera samples (the interior term,
// war, war-bdpt, was: diff/pixel_driver.h).
#pragma once
#include "render/path_tracer.h"

#include <cstdint>
#include <functional>

namespace penumbra {

struct PixelOptions {
    int spp = 16;    // samples per pixel (per batch)
    int batches = 1; // independent batches, for per-pixel standard errors (forward mode)
    uint64_t seed = 0;
    int threads = 0;   // 0 = all
    PathSettings path; // depth limits of the path sampler
    std::function<void(float)> progress;
};

} // namespace penumbra
