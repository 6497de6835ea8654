// Equal-time inverse-rendering race (paper 002 §5.3, Figures 1 and 9): recover BSDF parameters (e.g. a blend
// weight and a GGX roughness) from one target image with Adam, once with BSDF sampling and once with
// differential + adaptive sampling (both with NEE, path_sampling_loss_gradient). Each method's spp per
// iteration is calibrated so that an iteration takes the same CPU time (BSDF sampling runs at `spp`; CPU time of
// the process, all threads, as the variance study: wall time on a shared machine is disturbed by other
// processes), and each iteration logs the elapsed estimator CPU time, a low-noise loss (not timed: render() at
// `eval_spp` against a render of the truth with the same seed) and the parameter error. Outputs: a CSV of the
// histories and a PNG with loss and parameter error against time for both methods.
#pragma once
#include "core/image_loss.h"
#include "scene/scene.h"

#include <functional>
#include <string>
#include <vector>

namespace penumbra {

struct SamplingRaceOptions {
    std::vector<std::string> parameters; // BSDF / emitter parameters (one scalar each); the scene's values are the truth
    std::vector<float> initial;          // starting value of each parameter
    float lower = 0.01f, upper = 0.99f;  // box bounds of every parameter (weights and roughnesses)
    int iterations = 40;
    int spp = 8;                         // BSDF sampling's spp per iteration (all three passes)
    double learning_rate = 0.02;
    LossKind loss = LossKind::RelativeL2; // the paper's relative MSE
    int target_spp = 256, eval_spp = 32, calibration_runs = 5; // calibration: fastest of 5 runs per method
    uint64_t seed = 0;
    int threads = 0;
    std::string output = "race";         // directory for race.csv and race.png
    // Called after every iteration with the method's name and the iteration number (1-based).
    std::function<void(const std::string&, int)> progress;
};

struct RaceRecord {
    int iteration = 0;
    double seconds = 0;         // cumulative estimator CPU time (gradients only)
    double loss = 0;            // loss of a render at eval_spp against the truth's (same seed)
    double parameter_error = 0; // √(mean_k ((x_k − x*_k) / x*_k)²)
    std::vector<float> values;
};

struct RaceMethod {
    std::string name;
    bool differential = false, adaptive = false;
    int spp = 0;
    double seconds_per_iteration = 0; // measured mean CPU time over the iterations
    std::vector<RaceRecord> history;  // iteration 0 = the initial values
};

struct SamplingRaceResult {
    std::vector<std::string> parameters;
    std::vector<float> truth, initial;
    std::vector<RaceMethod> methods; // BSDF sampling, then differential + adaptive
    std::string csv_path, plot_path;
};

// Each parameter is recovered as one scalar broadcast over its components (a float texture stores 3 channels).
// Throws Error for unknown or geometric parameters, parameters whose components differ, a wrong number of initial values, or bad
// options. The scene is left at the true values.
SamplingRaceResult sampling_race(Scene& scene, const SamplingRaceOptions& options);

} // namespace penumbra
