// The vMF auxiliary distribution of warped-area sampling (paper 004 §4.1): normalization, sampling against
// the analytic CDF and mean, and the antithetic partner as a point reflection about the mean.
#include "core/rng.h"
#include "core/vmf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

using namespace penumbra;

namespace {

const Vec3f Mean = normalize(Vec3f(0.3f, -0.5f, 0.8f));

// ∫ p dω = 2π ∫_0^2 p(1 − cosθ) d(1 − cosθ), by Simpson's rule over the support that matters (e^{−κ t} >
// e^{−60}).
double integrate_pdf(float kappa) {
    const double top = std::fmin(2.0, 60.0 / kappa);
    const int n = 20000;
    const double h = top / n;
    double sum = 0.0;
    for (int i = 0; i <= n; ++i) {
        const double weight = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
        sum += weight * vmf_pdf(kappa, float(i * h));
    }
    return 2.0 * double(Pi) * sum * h / 3.0;
}

// P(1 − cosθ ≤ t) = (1 − e^{−κ t}) / (1 − e^{−2κ}), written with expm1; uniform in t/2 at κ → 0.
double cdf(double kappa, double t) {
    return kappa < 1e-8 ? t / 2.0 : std::expm1(-kappa * t) / std::expm1(-2.0 * kappa);
}

} // namespace

TEST(Vmf, PdfIntegratesToOne) {
    for (float kappa : {1e-3f, 0.01f, 1.f, 10.f, 1e3f, 1e5f, 1e6f}) {
        // Simpson's error on e^{−κ t} with 20000 intervals over ≤ 60/κ is < 1e-9; the float density rounds to
        // ~1e-7.
        EXPECT_NEAR(integrate_pdf(kappa), 1.0, 1e-5) << "kappa " << kappa;
    }
}

TEST(Vmf, SamplingMatchesCdfAndMean) {
    const Frame3f frame(Mean);
    for (float kappa : {0.01f, 1.f, 10.f, 1e3f, 1e5f}) {
        PCG32 rng(7, uint64_t(kappa * 1000));
        // Chi-square on 10 × 10 cells of (CDF(1 − cosθ), φ / 2π): uniform if the sampler follows the density.
        const int bins = 10, n = 100000;
        std::vector<int> cells(bins * bins, 0);
        double sum = 0.0, sum2 = 0.0;
        for (int i = 0; i < n; ++i) {
            const VmfSample s = sample_vmf(frame, kappa, Vec2f(rng.next_float(), rng.next_float()));
            ASSERT_NEAR(norm(s.direction), 1.f, 1e-5f);
            ASSERT_NEAR(s.pdf, vmf_pdf(kappa, s.one_minus_cos), 1e-6f * s.pdf);
            const double u = cdf(kappa, s.one_minus_cos);
            double phi = std::atan2(double(s.local.y), double(s.local.x)) / (2.0 * double(Pi));
            if (phi < 0.0) phi += 1.0;
            ++cells[std::min(bins - 1, int(u * bins)) * bins + std::min(bins - 1, int(phi * bins))];
            sum += s.one_minus_cos;
            sum2 += double(s.one_minus_cos) * s.one_minus_cos;
        }
        double chi2 = 0.0;
        const double expected = double(n) / (bins * bins);
        for (int c : cells)
            chi2 += (c - expected) * (c - expected) / expected;
        // 99 degrees of freedom: P(χ² > 160) ≈ 1e-4.
        EXPECT_LT(chi2, 160.0) << "kappa " << kappa;
        std::printf("vMF kappa %g: chi2 %.1f (99 dof)", double(kappa), chi2);
        // E[1 − cosθ] = 1/κ − 2 e^{−2κ} / (1 − e^{−2κ}) (1 − the mean resultant length coth κ − 1/κ).
        const double k = kappa;
        const double mean_exact = 1.0 / k - 2.0 / std::expm1(2.0 * k);
        const double mean = sum / n, se = std::sqrt((sum2 / n - mean * mean) / n);
        std::printf(", E[1 - cos] z = %.2f\n", (mean - mean_exact) / se);
        EXPECT_LT(std::abs(mean - mean_exact) / se, 4.0)
            << "kappa " << kappa << " mean " << mean << " exact " << mean_exact;
    }
}

TEST(Vmf, AntitheticIsPointReflectionAboutMean) {
    const Frame3f frame(Mean);
    PCG32 rng(3);
    for (float kappa : {0.01f, 10.f, 1e5f}) {
        for (int i = 0; i < 1000; ++i) {
            const VmfSample s = sample_vmf(frame, kappa, Vec2f(rng.next_float(), rng.next_float()));
            const VmfSample r = antithetic(frame, s);
            EXPECT_EQ(r.pdf, s.pdf);
            EXPECT_EQ(r.one_minus_cos, s.one_minus_cos);
            EXPECT_EQ(r.local.x, -s.local.x);
            EXPECT_EQ(r.local.y, -s.local.y);
            EXPECT_EQ(r.local.z, s.local.z);
            // Reflection through the mean's axis: ω' + ω'_r = 2 cosθ μ, and the partner has the same angle to
            // μ.
            const Vec3f sum = s.direction + r.direction - Mean * (2.f * s.local.z);
            EXPECT_LT(norm(sum), 1e-5f);
            EXPECT_NEAR(dot(r.direction, Mean), dot(s.direction, Mean), 1e-5f);
        }
    }
}
