// Inverse rendering with participating media (paper 001 §7.2; docs/differentiable-media.md): the demos of
// scenes/media_demos converge from their perturbed starts at a tiny resolution, with psdr gradients.
#include "optim/optimize.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

using namespace penumbra;
namespace fs = std::filesystem;

namespace {

const std::string demos = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/media_demos/";

OptimizeResult run_demo(const std::string& config_file, int res, int iterations, const std::string& out) {
    OptimizeConfig config = load_optimize_config(demos + config_file);
    config.defines["res"] = std::to_string(res);
    config.iterations = iterations;
    config.target_spp = 256;
    config.snapshot_every = 0;
    config.output = (fs::temp_directory_path() / out).string();
    fs::remove_all(config.output);
    OptimizeResult result = optimize(config);
    fs::remove_all(config.output);
    return result;
}

} // namespace

// (i) The position of a glass sphere in fog from its volumetric caustics (spheres.json): the translation
// error must fall by 5x.
TEST(MediaDemo, RecoversTheSpherePositionFromVolumetricCaustics) {
    const OptimizeResult r = run_demo("spheres.json", 16, 60, "penumbra_test_media_spheres");
    ASSERT_FALSE(r.history.empty());
    const IterationRecord& first = r.history.front();
    std::printf("  translation error %.4g -> %.4g, loss %.4g -> %.4g, %.1f s\n", first.translation_error,
                r.final_translation_error, first.loss, r.history.back().loss, r.seconds);
    EXPECT_EQ(r.method, "psdr");
    EXPECT_LT(r.final_translation_error, first.translation_error / 5);
}

// (ii) A translucent object's surface roughness and medium density jointly (translucent.json): the relative
// parameter error must fall by 5x.
TEST(MediaDemo, RecoversRoughnessAndDensityOfATranslucentObject) {
    const OptimizeResult r = run_demo("translucent.json", 16, 60, "penumbra_test_media_translucent");
    ASSERT_FALSE(r.history.empty());
    const IterationRecord& first = r.history.front();
    std::printf("  parameter error %.4g -> %.4g, loss %.4g -> %.4g, %.1f s\n", first.parameter_error,
                r.final_parameter_error, first.loss, r.history.back().loss, r.seconds);
    EXPECT_LT(r.final_parameter_error, first.parameter_error / 5);
}
