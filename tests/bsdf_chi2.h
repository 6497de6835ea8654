// Test helpers for BSDFs: a constant texture, and a chi-square goodness-of-fit test of sampled directions
// against their density on a (cos theta, phi) histogram (as Mitsuba's test suite does), for BSDF::sample
// against BSDF::pdf and for phase functions.
#pragma once
#include "core/rng.h"
#include "scene/bsdf.h"
#include "scene/texture.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace penumbra::test {

// Local constant texture, so that BSDF tests do not depend on the texture plugins.
class ConstantTex final : public TextureBase<ConstantTex> {
public:
    explicit ConstantTex(const Color3f& v) : v_(v) {}
    template <typename T> Color3<T> eval_t(const SurfaceInteraction<T>&) const { return Color3<T>(T(v_.x), T(v_.y), T(v_.z)); }
    Color3f mean() const override { return v_; }
    bool is_constant() const override { return true; }

private:
    Color3f v_;
};
inline std::shared_ptr<Texture> tex(float v) { return std::make_shared<ConstantTex>(Color3f(v)); }
inline std::shared_ptr<Texture> tex(const Color3f& v) { return std::make_shared<ConstantTex>(v); }

inline SurfaceInteraction3f make_si(const Vec3f& wi) {
    SurfaceInteraction3f si;
    si.wi = normalize(wi);
    si.uv = Vec2f(0.5f, 0.5f);
    return si;
}

// Upper tail probability of the chi-square distribution (Wilson-Hilferty cube-root normal approximation,
// accurate to a few percent of p for dof >= 10, which is all a significance threshold needs).
inline double chi2_upper_tail(double x, int dof) {
    const double k = dof;
    const double z = (std::cbrt(x / k) - (1.0 - 2.0 / (9.0 * k))) / std::sqrt(2.0 / (9.0 * k));
    return 0.5 * std::erfc(z / std::sqrt(2.0));
}

struct Chi2Result {
    double p_value = 0.0;
    std::string report;
};

// A chi-square goodness-of-fit test of sampled directions against their density: draws n directions with
// sample(rng, wo) (false: no direction, e.g. a failed or delta sample, not counted), histograms them over
// n_cos x n_phi bins of (cos theta in [-1, 1], phi in [0, 2 pi)) (equal solid angle per bin) and compares with
// n * int_bin pdf(wo), integrated with a sub x sub midpoint rule. Bins expecting fewer than 5 samples are pooled.
template <typename Sample, typename Pdf>
Chi2Result direction_chi2(Sample&& sample, Pdf&& pdf, int n, uint64_t seed, int n_cos = 20, int n_phi = 40,
                          int sub = 12) {
    std::vector<double> observed(size_t(n_cos * n_phi), 0.0), expected(size_t(n_cos * n_phi), 0.0);
    PCG32 rng(seed);
    for (int i = 0; i < n; ++i) {
        Vec3f wo;
        if (!sample(rng, wo)) continue;
        wo = normalize(wo);
        float phi = std::atan2(wo.y, wo.x);
        if (phi < 0.f) phi += 2.f * Pi;
        const int ic = std::clamp(int((wo.z + 1.f) * 0.5f * n_cos), 0, n_cos - 1);
        const int ip = std::clamp(int(phi / (2.f * Pi) * n_phi), 0, n_phi - 1);
        observed[size_t(ic * n_phi + ip)] += 1.0;
    }
    const double dz = 2.0 / n_cos, dphi = 2.0 * Pi / n_phi;
    for (int ic = 0; ic < n_cos; ++ic)
        for (int ip = 0; ip < n_phi; ++ip) {
            double sum = 0.0;
            for (int a = 0; a < sub; ++a)
                for (int b = 0; b < sub; ++b) {
                    const double z = -1.0 + dz * (ic + (a + 0.5) / sub);
                    const double phi = dphi * (ip + (b + 0.5) / sub);
                    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
                    const Vec3f wo(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z));
                    sum += pdf(wo);
                }
            expected[size_t(ic * n_phi + ip)] = n * sum * dz * dphi / (sub * sub);
        }
    double chi2 = 0.0, pooled_obs = 0.0, pooled_exp = 0.0;
    int dof = -1;
    std::ostringstream worst;
    double worst_term = 0.0;
    for (size_t i = 0; i < observed.size(); ++i) {
        if (expected[i] < 5.0) {
            pooled_obs += observed[i];
            pooled_exp += expected[i];
            continue;
        }
        const double term = (observed[i] - expected[i]) * (observed[i] - expected[i]) / expected[i];
        if (term > worst_term) {
            worst_term = term;
            worst.str("");
            worst << "bin (cos " << i / size_t(n_phi) << ", phi " << i % size_t(n_phi) << "): observed " << observed[i]
                  << ", expected " << expected[i];
        }
        chi2 += term;
        ++dof;
    }
    if (pooled_exp >= 5.0) {
        chi2 += (pooled_obs - pooled_exp) * (pooled_obs - pooled_exp) / pooled_exp;
        ++dof;
    } else if (pooled_obs > 5.0 + 5.0 * std::sqrt(std::max(pooled_exp, 1.0))) {
        // Samples where the pdf says there is (almost) nothing: a hard failure.
        return {0.0, "pooled low-density bins observed " + std::to_string(pooled_obs) + ", expected " +
                         std::to_string(pooled_exp)};
    }
    Chi2Result r;
    dof = std::max(dof, 1);
    r.p_value = chi2_upper_tail(chi2, dof);
    std::ostringstream os;
    os << "chi2 = " << chi2 << ", dof = " << dof << ", p = " << r.p_value << "; worst " << worst.str();
    r.report = os.str();
    return r;
}

// Draws n samples from bsdf at si and tests the non-delta directions against bsdf.pdf (direction_chi2).
inline Chi2Result bsdf_chi2(const BSDF& bsdf, const SurfaceInteraction3f& si, const BSDFContext& ctx, int n,
                            uint64_t seed, int n_cos = 20, int n_phi = 40, int sub = 12) {
    return direction_chi2(
        [&](PCG32& rng, Vec3f& wo) {
            const float u1 = rng.next_float();
            const Vec2f u2(rng.next_float(), rng.next_float());
            const auto [bs, w] = bsdf.sample(ctx, si, u1, u2);
            wo = bs.wo;
            return !(bs.pdf == 0.f || is_black(w) || (bs.sampled_type & BSDFDelta));
        },
        [&](const Vec3f& wo) { return double(bsdf.pdf(ctx, si, wo)); }, n, seed, n_cos, n_phi, sub);
}

} // namespace penumbra::test
