// What the adapters of the estimators behind the common front of diff/method.h (diff/*_method.cpp) share: an
// estimator's options for one run, and its results in the front's form.
#pragma once
#include "diff/method.h"
#include "diff/result.h"
#include "render/integrator_settings.h"

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

// The derivative of a method with one term (the whole derivative), named `term`.
inline MethodDerivative one_term_derivative(const DerivativeImage& d, const std::string& term,
                                            const std::string& description) {
    MethodDerivative out;
    out.derivative = d.derivative;
    out.stderr_img = d.stderr_img;
    out.terms.push_back({term, d.derivative, d.stderr_img});
    out.description = description;
    out.seconds = d.seconds;
    report_dropped_samples(out, d.cost.dropped);
    return out;
}

// An estimator's gradient (values, primal image, seconds, and the warnings where it has them) in the front's
// form.
template <typename EstimatedGradient>
MethodGradient method_gradient(const EstimatedGradient& g, const std::string& description) {
    MethodGradient out;
    out.values = g.values;
    out.primal = g.primal;
    if constexpr (requires { g.warnings; }) out.warnings = g.warnings;
    out.description = description;
    out.seconds = g.seconds;
    if constexpr (requires { g.cost.dropped; }) report_dropped_samples(out, g.cost.dropped);
    if constexpr (requires { g.dropped; }) report_dropped_samples(out, g.dropped);
    return out;
}

} // namespace penumbra
