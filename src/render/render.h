// Rendering entry point: runs the scene's integrator over the film.
#pragma once
#include "core/image.h"
#include "scene/scene.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace penumbra {

struct RenderOptions {
    int spp = 0;          // samples per pixel; 0 = the scene sampler's sample_count
    uint64_t seed = 0;    // the image is bit-identical for a given seed whatever the thread count
    int threads = 0;      // 0 = all hardware threads
    bool stratified = false; // film positions stratified within each pixel (core/stratified.h) instead of independent
    // Called with the completed fraction in [0,1] (from worker threads, serialized).
    std::function<void(float)> progress;
};

struct RenderStats {
    double seconds = 0;
    uint64_t samples = 0;  // camera samples (or light paths for ptracer)
    uint64_t rays = 0;     // rays cast (intersection + shadow)
    uint64_t dropped_samples = 0; // samples with a non-finite value, excluded from the estimate
};

struct Layer;

// Renders with the scene's integrator and returns its main image (or its first AOV).
Image render(const Scene& scene, const RenderOptions& options, RenderStats* stats = nullptr);
// Renders all layers (the main image is named "", AOVs by their names).
std::vector<Layer> render_layers(const Scene& scene, const RenderOptions& options, RenderStats* stats = nullptr);

} // namespace penumbra
