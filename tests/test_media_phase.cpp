// Phase functions (isotropic, Henyey-Greenstein): normalization and mean cosine by quadrature, sample()
// returning eval() as its density, a chi-square test of sampled directions against that density (with a
// check that the test rejects a slightly wrong g), and the sampled mean cosine against g.
#include "scene/factory.h"
#include "scene/phase.h"

#include "bsdf_chi2.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

using namespace penumbra;
using namespace penumbra::test;

namespace {

// An arbitrary incident direction: the tests must not depend on the frame.
const Vec3f kWi = normalize(Vec3f(0.3f, -0.5f, 0.8f));

std::shared_ptr<PhaseFunction> hg(float g) {
    Properties props("hg", SourceLocation{"phase", 1});
    props.set("g", double(g), SourceLocation{"phase", 1});
    auto phase = std::static_pointer_cast<PhaseFunction>(make_phase(props, LoadContext{}));
    phase->plugin = "hg";
    return phase;
}

std::shared_ptr<PhaseFunction> make(const std::string& name) {
    if (name == "isotropic") {
        auto phase = std::static_pointer_cast<PhaseFunction>(
            make_phase(Properties("isotropic", SourceLocation{"phase", 1}), LoadContext{}));
        phase->plugin = "isotropic";
        return phase;
    }
    return hg(std::stof(name.substr(3)));
}

float g_of(const std::string& name) { return name == "isotropic" ? 0.f : std::stof(name.substr(3)); }

// ∫ f(wo) dwo over the sphere: midpoint rule on a (z, phi) grid of world directions.
double sphere_integral(const std::function<double(const Vec3f&)>& f, int nz = 2000, int nphi = 800) {
    double sum = 0.0;
    for (int i = 0; i < nz; ++i) {
        const double z = -1.0 + 2.0 * (i + 0.5) / nz, r = std::sqrt(1.0 - z * z);
        for (int j = 0; j < nphi; ++j) {
            const double phi = 2.0 * Pi * (j + 0.5) / nphi;
            sum += f(Vec3f(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z)));
        }
    }
    return sum * (2.0 / nz) * (2.0 * Pi / nphi);
}

// Chi-square of n directions drawn by `phase` against the density of `pdf_of` (tests/bsdf_chi2.h).
test::Chi2Result phase_chi2(const PhaseFunction& phase, const PhaseFunction& pdf_of, int n, uint64_t seed) {
    return test::direction_chi2(
        [&](PCG32& rng, Vec3f& wo) {
            const Vec2f u(rng.next_float(), rng.next_float());
            wo = phase.sample(kWi, u).first;
            return true;
        },
        [&](const Vec3f& wo) { return double(pdf_of.pdf(kWi, wo)); }, n, seed);
}

class MediaPhase : public ::testing::TestWithParam<std::string> {};

} // namespace

// ∫ p dwo = 1 and ∫ p (-wi · wo) dwo = g (HG's mean cosine about the forward direction -wi: the sign
// convention). Deterministic: the midpoint rule on this grid is within 2e-7 of both for every g tested
// (measured); 1e-5 leaves room for float rounding, while a wrong constant or sign is off by 1e-2 or more.
TEST_P(MediaPhase, NormalizedWithMeanCosineG) {
    const auto phase = make(GetParam());
    const float g = g_of(GetParam());
    const double total =
        sphere_integral([&](const Vec3f& wo) { return double(phase->eval<float>(kWi, wo)); });
    const double mean_cos =
        sphere_integral([&](const Vec3f& wo) { return double(phase->eval<float>(kWi, wo)) * -dot(kWi, wo); });
    std::printf("  %s: integral - 1 = %.2e, mean cosine - g = %.2e\n", GetParam().c_str(), total - 1.0,
                mean_cos - g);
    EXPECT_NEAR(total, 1.0, 1e-5);
    EXPECT_NEAR(mean_cos, g, 1e-5);
}

TEST_P(MediaPhase, SampleReturnsEvalAsDensityAndMeanCosineG) {
    const auto phase = make(GetParam());
    const float g = g_of(GetParam());
    PCG32 rng(3);
    constexpr int n = 100000;
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < n; ++i) {
        const auto [wo, pdf] = phase->sample(kWi, Vec2f(rng.next_float(), rng.next_float()));
        ASSERT_NEAR(norm(wo), 1.f, 1e-5f);
        // The density is evaluated by the same formula: only float rounding of the direction separates them.
        ASSERT_NEAR(pdf, phase->eval<float>(kWi, wo), 1e-5f * pdf) << "sample " << i;
        ASSERT_NEAR(pdf, phase->pdf(kWi, wo), 1e-5f * pdf);
        const double c = -dot(kWi, wo);
        sum += c;
        sum2 += c * c;
    }
    // z-test of the sampled mean cosine (|z| < 4.5: false alarm 7e-6 per check).
    const double mean = sum / n, se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / (n - 1));
    const double z = (mean - g) / se;
    std::printf("  %s: sampled mean cosine %.5f (g = %g), z %+.2f\n", GetParam().c_str(), mean, g, z);
    EXPECT_LT(std::abs(z), 4.5);
}

// p > 1e-4 over 5 configurations: a correct sampler fails with probability 5e-4 (and the seed is fixed).
TEST_P(MediaPhase, ChiSquareOfSampledDirections) {
    const auto phase = make(GetParam());
    const test::Chi2Result r = phase_chi2(*phase, *phase, 200000, 7);
    std::printf("  %s: %s\n", GetParam().c_str(), r.report.c_str());
    EXPECT_GT(r.p_value, 1e-4) << r.report;
}

INSTANTIATE_TEST_SUITE_P(Media, MediaPhase,
                         ::testing::Values("isotropic", "hg_-0.7", "hg_0", "hg_0.3", "hg_0.9"),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                             std::string s = info.param;
                             for (char& c : s)
                                 if (c == '-')
                                     c = 'm';
                                 else if (c == '.')
                                     c = 'p';
                             return s;
                         });

// The chi-square test has the power to see a small error: samples of g = 0.3 against the density of g = 0.36.
TEST(MediaPhaseChi2, RejectsSlightlyWrongAsymmetry) {
    const test::Chi2Result r = phase_chi2(*hg(0.3f), *hg(0.36f), 200000, 7);
    std::printf("  g 0.3 vs 0.36: %s\n", r.report.c_str());
    EXPECT_LT(r.p_value, 1e-6) << r.report;
}
