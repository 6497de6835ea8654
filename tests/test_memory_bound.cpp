// Memory does not grow with the sample count or the iteration count (issue 18): the peak resident set
// (getrusage) after a render, a forward-mode derivative and a reverse-mode gradient at 16x the samples, and
// after 200 optimization iterations against 20, grows by less than 10%. (ctest runs each test in its own
// process, so the peak is this test's.)
#include "optim/optimize.h"
#include "robustness_test_util.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cstdio>
#include <filesystem>

using namespace penumbra;
using namespace penumbra::test;
namespace fs = std::filesystem;

namespace {

double peak_rss_mb() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return double(usage.ru_maxrss) / 1024.0;
}

} // namespace

TEST(MemoryBound, PeakMemoryDoesNotGrowWithSamples) {
    auto scene = load_scene(PENUMBRA_SOURCE_DIR "/scenes/cbox/cbox.xml", {{"res", "24"}});
    render_and_differentiate(*scene, "tall_box.translate=1,0,0", "psdr", 4, 4);
    const double at_4 = peak_rss_mb();
    render_and_differentiate(*scene, "tall_box.translate=1,0,0", "psdr", 64, 64);
    const double at_64 = peak_rss_mb();
    std::printf("  peak RSS: %.1f MB at 4 spp, %.1f MB at 64 spp\n", at_4, at_64);
    EXPECT_LT(at_64, 1.1 * at_4);
}

TEST(MemoryBound, PeakMemoryDoesNotGrowWithIterations) {
    OptimizeConfig config = load_optimize_config(PENUMBRA_SOURCE_DIR "/scenes/optimize/config.json");
    config.defines["res"] = "12";
    config.spp = config.gradient_spp = 2;
    config.target_spp = 16;
    config.snapshot_every = 0;
    config.output = (fs::temp_directory_path() / "penumbra_test_memory_bound").string();
    fs::remove_all(config.output);
    config.iterations = 20;
    optimize(config);
    const double at_20 = peak_rss_mb();
    config.iterations = 200;
    optimize(config);
    const double at_200 = peak_rss_mb();
    std::printf("  peak RSS: %.1f MB after 20 iterations, %.1f MB after 200 more\n", at_20, at_200);
    EXPECT_LT(at_200, 1.1 * at_20);
    fs::remove_all(config.output);
}
