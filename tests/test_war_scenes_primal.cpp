// The primal images of paper 000's test scenes (scenes/war/, docs/war-scenes.md): each scene's path and bdpt
// variants (-D integrator=...) must agree within standard errors (z of the image mean and of 4 × 4 blocks
// over independent renders, as in test_bdpt_agreement.cpp), and on the caustic, where the floor is lit
// through the lens, bdpt must be the more efficient one (per-pixel variance times render time).
#include "test_bdpt_util.h"

#include <cstdio>
#include <cstdlib>
#include <string>

using namespace penumbra;
using namespace penumbra::test;

namespace {

const std::string scene_dir = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/war/";

uint64_t test_seed() {
    // PENUMBRA_TEST_SEED re-runs the checks with other random numbers (to see that they do not pass by luck).
    const char* env = std::getenv("PENUMBRA_TEST_SEED");
    return env ? std::strtoull(env, nullptr, 10) : 0;
}

std::unique_ptr<Scene> load_variant(const std::string& name, const std::string& integrator) {
    return load_scene(scene_dir + name + ".xml", {{"res", "16"}, {"integrator", integrator}});
}

struct Agreement {
    BlockStats bdpt, path;
    std::vector<double> z;
};

// 12 renders of each at 16 × 16; path tracing gets 4 × bdpt's samples (about its cost per sample).
Agreement agreement(const std::string& name, int bdpt_spp) {
    const uint64_t seed = 1 + 100003 * test_seed();
    Agreement a;
    a.bdpt = block_stats(*load_variant(name, "bdpt"), 12, bdpt_spp, seed);
    a.path = block_stats(*load_variant(name, "path"), 12, 4 * bdpt_spp, seed + 50021);
    a.z = z_scores(a.bdpt, a.path);
    std::printf(
        "[%s] bdpt mean %.5f (%d spp, %.3f s) vs path %.5f (%d spp, %.3f s), z = %.2f, max block |z| = "
        "%.2f; per-pixel variance x time: bdpt %.3g, path %.3g\n",
        name.c_str(), a.bdpt.mean[0], bdpt_spp, a.bdpt.seconds, a.path.mean[0], 4 * bdpt_spp, a.path.seconds,
        a.z[0], max_abs(a.z, 1), a.bdpt.pixel_variance * a.bdpt.seconds,
        a.path.pixel_variance * a.path.seconds);
    return a;
}

class WarScenePrimal : public testing::TestWithParam<std::string> {};

void expect_agreement(const Agreement& a) {
    EXPECT_GT(a.bdpt.mean[0], 0.0);
    EXPECT_LT(std::abs(a.z[0]), 4.0);
    EXPECT_LT(max_abs(a.z, 1), 4.5);
}

TEST_P(WarScenePrimal, BdptAgreesWithPath) { expect_agreement(agreement(GetParam(), 32)); }

INSTANTIATE_TEST_SUITE_P(WarScenes, WarScenePrimal, testing::Values("teapot", "glass_box", "star_light"));

TEST(WarScenePrimalCaustic, BdptAgreesWithPathAndIsMoreEfficient) {
    const Agreement a = agreement("caustic", 32);
    expect_agreement(a);
    const double ratio = (a.bdpt.pixel_variance * a.bdpt.seconds) / (a.path.pixel_variance * a.path.seconds);
    std::printf("[caustic] variance x time of bdpt / path: %.4f\n", ratio);
    EXPECT_LT(ratio, 0.5);
}

} // namespace
