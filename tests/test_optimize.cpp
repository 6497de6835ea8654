// The bundled inverse-rendering demo (scenes/optimize) recovers an albedo, a GGX roughness and an emitter
// radiance from a target rendered at the true values.
#include "optim/optimize.h"

#include <gtest/gtest.h>

#include <filesystem>

using namespace penumbra;
namespace fs = std::filesystem;

// Reduced settings: 56x56 instead of 64x64 and 160 iterations instead of 200 (the rate decay to 0.1x is
// compressed accordingly); 16 spp for the primal and the gradient as in the demo. 10-17 s on 2 shared cores.
// Why 2% is reachable: at exactly these settings the final relative errors over seeds 0-5 were
//   albedo 0.15-0.70%, radiance 0.16-0.67%, roughness 0.29-1.46% (seed 0: 0.26%, 0.20%, 1.46%).
// The roughness is the noisiest: it is seen only in the metal's highlight (a few dozen pixels), and the last
// steps (rate ~0.002) still jitter by ~1% of alpha = 0.2. Runs are deterministic for a seed, so this test is
// too. (At 48x48 the roughness settled ~1% high on every seed, up to 3.6%: too few highlight pixels.)
TEST(Optimize, DemoRecoversAlbedoRoughnessAndRadiance) {
    OptimizeConfig config = load_optimize_config(PENUMBRA_SOURCE_DIR "/scenes/optimize/config.json");
    config.defines["res"] = "56";
    config.iterations = 160;
    config.seed = 0;
    config.snapshot_every = 50;
    config.output = (fs::temp_directory_path() / "penumbra_test_optimize").string();
    fs::remove_all(config.output);

    const OptimizeResult result = optimize(config);

    ASSERT_EQ(result.history.size(), 160u);
    ASSERT_EQ(result.parameters.size(), 3u);
    for (const ParameterResult& p : result.parameters)
        EXPECT_LT(p.relative_error, 0.02) << p.name;
    // The loss fell by more than an order of magnitude from the initial guess.
    EXPECT_LT(result.history.back().loss, 0.1 * result.history.front().loss);
    for (const char* file : {"log.csv", "loss.png", "parameter_error.png", "result.json", "final.png",
                             "target.exr", "iter_0000.png", "iter_0100.png"})
        EXPECT_TRUE(fs::exists(fs::path(config.output) / file)) << file;
    fs::remove_all(config.output);
}
