// The DPM inverse-rendering demos (scenes/dpm/egg, scenes/dpm/wine; docs/dpm-demos.md) at a reduced size:
// each bundled configuration must recover its parameter from a wrong start.
#include "core/image.h"
#include "diff/dpm/dpm.h"
#include "diff/method.h"
#include "diff_cases.h"
#include "optim/optimize.h"
#include "render/render.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

using namespace penumbra;
namespace fs = std::filesystem;

namespace {

const std::string dpm_dir = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/dpm/";

struct Reduction {
    int res, photons, iterations;
    int passes = 0;      // primal and gradient SPPM passes (0: the configuration's)
    double lr_scale = 1; // learning rates times this
};

// The demo's configuration reduced, writing to a temporary directory; seed 1 + 1000 · test_seed().
OptimizeConfig reduced(const std::string& config_path, const Reduction& r, const std::string& name) {
    OptimizeConfig config = load_optimize_config(dpm_dir + config_path);
    config.defines["res"] = std::to_string(r.res);
    config.defines["photons"] = std::to_string(r.photons);
    config.iterations = r.iterations;
    if (r.passes > 0) config.spp = config.gradient_spp = r.passes;
    for (OptimizedParameter& p : config.parameters)
        p.learning_rate *= r.lr_scale;
    config.target_spp = 64;
    config.snapshot_every = 0;
    config.seed = 1 + 1000 * test::test_seed();
    config.output = (fs::temp_directory_path() / name).string();
    fs::remove_all(config.output);
    return config;
}

// The reduced configuration's optimization: its error (a pose's translation error, else the parameter error)
// must end below a quarter of where it started, with the configuration's method.
void expect_recovers(const std::string& config_path, const Reduction& r, const std::string& name,
                     const std::string& method, bool pose) {
    const OptimizeConfig config = reduced(config_path, r, name);
    const OptimizeResult result = optimize(config);
    ASSERT_EQ(result.history.size(), size_t(r.iterations));
    const IterationRecord& start = result.history.front();
    const double first = pose ? start.translation_error : start.parameter_error;
    const double last = pose ? result.final_translation_error : result.final_parameter_error;
    std::printf("  %s error %.4g -> %.4g, %.1f s\n", pose ? "translation" : "parameter", first, last,
                result.seconds);
    EXPECT_EQ(result.method, method);
    EXPECT_LT(last, first / 4);
    fs::remove_all(config.output);
}

} // namespace

// DPM-C with the L2 loss recovers the area light's height above the glass egg from the caustic, 0.4 units off
// at the start (32², 20,000 photons, 4 + 4 passes, twice the rates, 40 iterations: final errors 0.0029,
// 0.0114, 0.0104 over test seeds 0-2, 6-7 s on the 2 shared cores; with 8 + 8 passes 0.008-0.037 over seeds
// 0-5 in 10-19 s; the last steps' gradient noise sets the spread).
TEST(DpmDemos, EggRecoversTheLightHeight) {
    expect_recovers("egg/config_dpm_c.json", {32, 20000, 40, 4, 2.0}, "penumbra_test_dpm_egg", "dpm-c", true);
}

// DPM-G with the matching loss (the demo's own configuration, scenes/dpm/egg/config.json, with its default
// jackknife) recovers the height too (24², 20,000 photons, 4 + 4 passes, twice the rate, 30 iterations: 0.4
// -> 0.0143, 0.0454, 0.0340 over test seeds 0-2, 7-12 s on the 2 shared cores; at 32² 0.0057, 0.0146, 0.0093
// in 32-37 s: the matching's optimal transport grows with the square of the pixel count).
TEST(DpmDemos, EggRecoversTheLightHeightWithTheMatchingLoss) {
    expect_recovers("egg/config.json", {24, 20000, 30, 4, 2.0}, "penumbra_test_dpm_egg_g", "dpm-g", true);
}

// DPM-C with the L2 loss recovers the liquid's colour (specular_transmittance) from its coloured caustic
// (32², 10,000 photons, 4 + 4 passes, twice the rates, 30 iterations: 0.86 -> 0.13-0.15 over test seeds 0-5,
// 4 s; the blue and green components, whose caustic is dim, converge last).
TEST(DpmDemos, WineRecoversTheLiquidColour) {
    expect_recovers("wine/config.json", {32, 10000, 30, 4, 2.0}, "penumbra_test_dpm_wine", "dpm-c", false);
}

// At the egg's solution (light at height 1.6), the matching loss's gradient along the light's height should
// vanish: over 24 seeds its mean within 4 standard errors of 0 (t with 23 dof). The matching is a nonlinear
// function of the noisy matched image, so the plain matching's gradient is biased at finite passes
// (docs/dpm.md); the default jackknife over two halves of the passes removes that bias. The target is the
// expected image, stored (tests/data/dpm/egg_solution.exr: 1024 passes of 20,000 photons,
// scripts/make_dpm_references.sh; at a fixed radius the expectation does not depend on the photon count), so
// that its noise adds no offset common to the seeds. 5,000 photons make the matched image noisy enough for
// the plain bias to show (32², 8 passes, every pixel, 2 paths): over test seeds 0-2 the jackknife's mean is
// −1.15, −0.02, +0.10 standard errors from 0, the plain matching's −7.8, −5.4, −5.1 (−0.047, −0.034, −0.031,
// 1.0-1.6 standard deviations of one seed's gradient: over 16 seeds it would pass at seed 1, −3.9). With
// 20,000 photons and 1 path the plain bias was 0.6 standard deviations per seed (docs/dpm.md). 28-30 s on the
// 2 shared cores at load 4-5 (18-19 s with the plain matching).
TEST(DpmDemos, EggMatchingGradientVanishesAtTheSolution) {
    const std::map<std::string, std::string> defines = {
        {"res", "32"}, {"photons", "5000"}, {"radius", "0.012"}, {"light_y", "1.6"}};
    auto scene = load_scene(dpm_dir + "egg/scene.xml", defines);
    const Image target =
        read_image(std::string(PENUMBRA_SOURCE_DIR) + "/tests/data/dpm/egg_solution.exr", false);
    Parameters params(*scene);
    params.enable({parse_param_selection("light.translate=0,1,0")});
    const int seeds = 24;
    double sum = 0, sum2 = 0;
    for (int k = 0; k < seeds; ++k) {
        DpmOptions options;
        options.variant = DpmVariant::G;
        options.spp = 8;
        options.pixel_fraction = 1;
        options.paths = 2;
        options.seed = 1 + k + 1000 * test::test_seed();
        const double g = dpm_matching_gradient(*scene, params, target, options).values.at(0);
        sum += g;
        sum2 += g * g;
    }
    const double mean = sum / seeds, se = std::sqrt((sum2 / seeds - mean * mean) / (seeds - 1));
    std::printf("  dL/dy at the solution: %.4g +- %.4g (z %.2f)\n", mean, se, mean / se);
    EXPECT_LT(std::abs(mean), 4 * se);
}
