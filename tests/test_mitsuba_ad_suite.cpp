// The Mitsuba differentiable-rendering test suite (scenes/mitsuba_ad/suite.json, studies/ad_suite.h) at each
// scene's reduced CI resolution: psdr's derivative at Mitsuba's sample count, split by psdr_budget, against
// the central differences that `penumbra ad-suite` stored in scenes/mitsuba_ad/fd at ci_res (or, when a scene
// changed since, computed here at the same settings: slow; regenerate the cache as suite.json says).
// `penumbra ad-suite` measures the same at 128².
#include "studies/ad_suite.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

using namespace penumbra;

namespace {

const std::string manifest = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/mitsuba_ad/suite.json";
const std::string reference_cache = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/mitsuba_ad/fd";
// The seed of the stored references (penumbra ad-suite's): independent of the derivative's seeds.
constexpr uint64_t ReferenceSeed = 2;

// The accuracy bar: relerr after 4 × 4 block averaging, where noise averages out and a bias does not.
constexpr double MaxRelerr4 = 0.05;
// The reference's own relerr4 noise must stay well below the bar, or the comparison could not see a bias.
constexpr double MaxReferenceNoise4 = 0.02;
// Unbiasedness of the image mean: the derivative's standard error comes from 8 batches and the reference's from
// 16, so z is t-like with ~10 degrees of freedom: P(|z| > 4) ~ 0.3%.
constexpr double MaxMeanZ = 4.0;

bool passes(const AdSuiteScore& s) { return s.blocks.relerr <= MaxRelerr4 && std::abs(s.full.mean_z) < MaxMeanZ; }

std::string describe(const AdSuiteScore& s) {
    return "relerr " + std::to_string(s.full.relerr) + ", relerr4 " + std::to_string(s.blocks.relerr) + " (noise " +
           std::to_string(s.blocks.noise_relerr) + ", reference alone " + std::to_string(s.reference_noise4) +
           "), z of the mean " + std::to_string(s.full.mean_z);
}

// Test names are the manifest's scene names; a manifest that does not load gives one test that reports why.
std::vector<std::string> scene_names() {
    try {
        std::vector<std::string> names;
        for (const AdSuiteScene& s : load_ad_suite(manifest).scenes) names.push_back(s.name);
        return names;
    } catch (const Error&) {
        return {"manifest"};
    }
}

class MitsubaAdScene : public testing::TestWithParam<std::string> {};

TEST_P(MitsubaAdScene, MatchesFiniteDifferences) {
    const AdSuite suite = load_ad_suite(manifest);
    const AdSuiteScene* found = nullptr;
    for (const AdSuiteScene& s : suite.scenes) found = s.name == GetParam() ? &s : found;
    ASSERT_NE(found, nullptr);
    const AdSuiteScene& s = *found;
    if (const std::vector<std::string> missing = missing_files(s); !missing.empty()) {
        ASSERT_TRUE(s.optional) << s.name << " needs " << missing[0];
        GTEST_SKIP() << s.name << ": " << missing[0] << " is absent";
    }
    // PENUMBRA_TEST_SEED re-runs the check with other random numbers (to see that it does not pass by luck).
    const char* env = std::getenv("PENUMBRA_TEST_SEED");
    const uint64_t seed = env ? std::strtoull(env, nullptr, 10) : 0;
    AdSuiteCase c = load_case(s, s.ci_res);
    const FdSettings ref = fd_settings(suite, s, s.ci_res);
    const std::optional<FiniteDifference> stored =
        read_cached_reference(reference_cache, s, s.ci_res, ref.eps, ref.spp, {}, ReferenceSeed);
    if (!stored)
        std::printf("  %s: no stored reference matches the scene; computing it (slow)\n", s.name.c_str());
    const FiniteDifference fd =
        stored ? *stored
               : suite_reference(*c.scene, *c.params, ref.eps, ref.spp, ReferenceSeed + 1000 * seed, 0);
    const DerivativeImage d = suite_derivative(*c.scene, *c.params, s.spp, 1 + 1000 * seed, 0);
    const AdSuiteScore total = score(d.derivative, d.stderr_img, fd);
    const AdSuiteScore interior = score(d.term("interior").derivative, d.term("interior").stderr_img, fd);
    std::printf("  %s at %dx%d, %d spp: %s\n  interior only: %s\n", s.name.c_str(), s.ci_res, s.ci_res, s.spp,
                describe(total).c_str(), describe(interior).c_str());

    EXPECT_LE(total.reference_noise4, MaxReferenceNoise4) << "the reference is too noisy to judge the derivative";
    // The negative control: without its boundary terms the derivative must fail the same check.
    EXPECT_FALSE(passes(interior)) << "the check cannot tell the interior term alone from the full derivative: "
                                   << describe(interior);
    EXPECT_TRUE(passes(total)) << describe(total);
}

INSTANTIATE_TEST_SUITE_P(MitsubaAd, MitsubaAdScene, testing::ValuesIn(scene_names()),
                         [](const testing::TestParamInfo<std::string>& info) { return info.param; });

} // namespace
