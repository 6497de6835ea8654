// What the adapters of the estimators behind the common front of diff/method.h (diff/*/*_method.cpp) share:
// an estimator's options for one run.
#pragma once
#include "diff/method.h"
#include "scene/integrator_settings.h"

#include <algorithm>

namespace penumbra {

// `o` with the run's samples per pixel split over `batches` (1 in reverse mode), its seed, threads and
// progress, and the scene's path settings.
template <typename Options>
Options run_options(Options o, const Scene& scene, const MethodRun& run, int batches) {
    o.batches = batches;
    o.spp = std::max(1, run.spp / batches);
    o.seed = run.seed;
    o.threads = run.threads;
    o.path = path_settings(scene);
    o.progress = run.progress;
    return o;
}

} // namespace penumbra
