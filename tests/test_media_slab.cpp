// Free-flight sampling and transmittance in a medium of constant extinction against the closed forms of a
// slab of thickness d: Tr = exp(-sigma_t d) per channel, the scattering expectation
// E[w 1(t < d)] = ∫_0^d Tr(t) sigma_s dt = albedo (1 - exp(-sigma_t d)) and its first moment in t
// E[w t 1(t < d)] = albedo (1 - exp(-sigma_t d)(1 + sigma_t d)) / sigma_t. The homogeneous medium uses the
// closed-form sampler; a heterogeneous medium with a constant sigma_t goes through delta and ratio tracking.
#include "render/medium_sampling.h"

#include "media_test_util.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace penumbra;
using namespace penumbra::test;

namespace {

// Every check is a z-test of a mean over N independent samples. |z| < 4.5 fails a correct estimator with
// probability 7e-6 per check (below 1e-3 over the whole media suite); the smallest bias detected is 4.5
// standard errors, printed with each check (well under 1% of the expected values here).
constexpr double kMaxZ = 4.5;
constexpr int kSamples = 200000;

struct SlabCase {
    const char* name;
    const char* medium_type;
    Color3f sigma_t, albedo;
};

void PrintTo(const SlabCase& c, std::ostream* os) { *os << c.name; }

class MediaSlab : public ::testing::TestWithParam<SlabCase> {};

std::string medium_xml(const SlabCase& c) {
    auto rgb = [](const Color3f& v) {
        return std::to_string(v.x) + ", " + std::to_string(v.y) + ", " + std::to_string(v.z);
    };
    return std::string("<medium type=\"") + c.medium_type +
           "\" name=\"interior\">\n<rgb name=\"sigma_t\" value=\"" + rgb(c.sigma_t) +
           "\"/>\n<rgb name=\"albedo\" value=\"" + rgb(c.albedo) + "\"/>\n</medium>";
}

void expect_z(const ChannelStats& s, int c, double expected, const std::string& what) {
    const double z = s.z(c, expected);
    EXPECT_LT(std::abs(z), kMaxZ) << what << " channel " << c << ": mean " << s.mean(c) << " expected "
                                  << expected << " stderr " << s.stderr_(c) << " z " << z;
    std::printf("  %-28s c%d  mean %.5f  expected %.5f  z %+.2f  (detects bias > %.2g)\n", what.c_str(), c,
                s.mean(c), expected, z, kMaxZ * s.stderr_(c));
}

} // namespace

TEST_P(MediaSlab, FreeFlightAndTransmittanceMatchClosedForms) {
    const SlabCase& k = GetParam();
    TempDir dir;
    const auto medium = load_medium(medium_xml(k), dir.str());
    ASSERT_TRUE(medium);
    const Vec3f o(0.2f, -0.1f, 0.3f), d = normalize(Vec3f(0.3f, 0.4f, 1.f));
    const float depth = 1.3f;

    ChannelStats passed, scattered, scattered_t, tr_estimate;
    double pass_count = 0;
    Sampler sampler;
    for (int i = 0; i < kSamples; ++i) {
        sampler.start(17, 0, uint64_t(i));
        const FreeFlightSample s = sample_free_flight(*medium, o, d, depth, sampler);
        const bool pass = s.event == FreeFlightSample::Event::Passed;
        const bool scatter = s.event == FreeFlightSample::Event::Scattered;
        if (scatter) {
            ASSERT_LT(s.t, depth);
            ASSERT_NEAR(norm(s.p - (o + d * s.t)), 0.f, 1e-5f);
        }
        pass_count += pass;
        passed.add(pass ? s.weight : Color3f(0.f));
        scattered.add(scatter ? s.weight : Color3f(0.f));
        scattered_t.add(scatter ? s.weight * s.t : Color3f(0.f));
        tr_estimate.add(transmittance(*medium, o, d, depth, sampler));
    }
    double mean_tr = 0;
    for (int c = 0; c < 3; ++c) {
        const double sigma = k.sigma_t[c], albedo = k.albedo[c], tr = std::exp(-sigma * depth);
        mean_tr += tr / 3;
        expect_z(passed, c, tr, "E[w 1(pass)] = Tr");
        expect_z(scattered, c, albedo * (1 - tr), "E[w 1(scatter)]");
        expect_z(scattered_t, c, sigma > 0 ? albedo * (1 - tr * (1 + sigma * depth)) / sigma : 0.0,
                 "E[w t 1(scatter)]");
        if (medium->is_homogeneous())
            EXPECT_NEAR(tr_estimate.mean(c), tr, 1e-6 * tr + 1e-7)
                << "closed-form transmittance, channel " << c;
        else
            expect_z(tr_estimate, c, tr, "ratio tracking Tr");
    }
    if (medium->is_homogeneous()) {
        // The channel is picked uniformly, so the distance passes d with probability mean_c Tr_c (binomial).
        const double p = pass_count / kSamples, se = std::sqrt(mean_tr * (1 - mean_tr) / kSamples);
        const double z = (p - mean_tr) / se;
        std::printf("  %-28s     mean %.5f  expected %.5f  z %+.2f\n", "P(pass)", p, mean_tr, z);
        EXPECT_LT(std::abs(z), kMaxZ) << "pass probability " << p << " expected " << mean_tr;
    }
}

// Chromatic extinction, one channel without extinction (a channel-balance weight is needed: dividing by the
// sampled channel's density alone would be biased there), and the tracking path with a constant grid.
INSTANTIATE_TEST_SUITE_P(
    Media, MediaSlab,
    ::testing::Values(
        SlabCase{"homogeneous_chromatic", "homogeneous", {0.5f, 1.f, 2.f}, {0.9f, 0.5f, 0.2f}},
        SlabCase{"homogeneous_zero_channel", "homogeneous", {0.f, 0.7f, 3.f}, {0.8f, 0.6f, 0.95f}},
        SlabCase{"tracking_chromatic", "heterogeneous", {0.5f, 1.f, 2.f}, {0.9f, 0.5f, 0.2f}},
        SlabCase{"tracking_zero_channel", "heterogeneous", {0.f, 0.7f, 3.f}, {0.8f, 0.6f, 0.95f}}),
    [](const ::testing::TestParamInfo<SlabCase>& info) { return std::string(info.param.name); });
