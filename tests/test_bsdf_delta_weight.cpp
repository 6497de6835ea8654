// BSDF::delta_weight (paper 003 §4.2.2, the smooth factor g of a delta lobe): for every BSDF with delta lobes
// it equals the sampled lobe's weight times its selection probability, for incident directions on both sides
// and in both transport modes; the Var evaluation has the float value and, for the Fresnel-weighted lobes, the
// derivative of central differences in the incident angle; wrappers (twosided, blend, mask, normalmap) pass
// it on, and smooth BSDFs have none.
#include "bsdf_chi2.h"
#include "core/var.h"
#include "scene/bsdfs/bsdfs.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace penumbra;
using namespace penumbra::test;

namespace {

struct Case {
    const char* name;
    BSDFPtr bsdf;
};

std::vector<Case> delta_bsdfs() {
    return {
        {"dielectric", make_dielectric(1.5f, tex(0.9f), tex(0.8f))},
        {"dielectric_inverse", make_dielectric(1.f / 1.33f, tex(1.f), tex(0.7f))},
        {"conductor", make_conductor(tex(0.2f), tex(3.f), tex(0.9f))},
        {"thindielectric", make_thindielectric(1.5f, tex(0.9f), tex(0.6f))},
        {"plastic", make_plastic(1.5f, tex(0.5f), tex(0.8f), false)},
        {"null", make_null_bsdf()},
        {"twosided_conductor", make_twosided(make_conductor(tex(0.2f), tex(3.f), tex(0.9f)), nullptr)},
        {"blend_dielectric_diffuse", make_blendbsdf(tex(0.3f), make_dielectric(1.5f, tex(1.f), tex(1.f)),
                                                    make_diffuse(tex(0.5f)))},
        {"mask_conductor", make_mask(tex(0.6f), make_conductor(tex(0.2f), tex(3.f), tex(0.9f)))},
        {"normalmap_dielectric",
         make_normalmap(tex(Color3f(0.6f, 0.45f, 0.95f)), make_dielectric(1.5f, tex(0.9f), tex(0.8f)))},
    };
}

float max_relative_difference(const Color3f& a, const Color3f& b) {
    float d = 0.f;
    for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(a[c] - b[c]) / std::max(1e-6f, std::abs(b[c])));
    return d;
}

} // namespace

// g(wi → wo) = sampled weight × probability of the sampled delta lobe, at every delta sample.
TEST(BsdfDeltaWeight, EqualsTheSampledLobesWeightTimesItsProbability) {
    const Vec3f directions[] = {{0.3f, 0.2f, 0.93f}, {-0.6f, 0.1f, 0.5f}, {0.1f, -0.7f, 0.2f},
                                {0.2f, 0.3f, -0.9f}, {-0.5f, 0.4f, -0.3f}};
    for (const Case& c : delta_bsdfs())
        for (const TransportMode mode : {TransportMode::Radiance, TransportMode::Importance}) {
            const BSDFContext ctx{mode};
            int checked = 0;
            for (const Vec3f& wi : directions) {
                const SurfaceInteraction3f si = make_si(wi);
                for (int k = 0; k < 64; ++k) {
                    const float u1 = (float(k) + 0.5f) / 64.f;
                    const auto [bs, weight] = c.bsdf->sample(ctx, si, u1, Vec2f(0.3f, 0.7f));
                    if (!(bs.sampled_type & BSDFDelta) || is_black(weight)) continue;
                    const Color3f expected = weight * bs.pdf;
                    const Color3f g = c.bsdf->delta_weight(ctx, si, bs.wo);
                    EXPECT_LE(max_relative_difference(g, expected), 1e-4f)
                        << c.name << ", wi (" << wi.x << ", " << wi.y << ", " << wi.z << "), u1 " << u1 << ": g ("
                        << g.x << ", " << g.y << ", " << g.z << ") vs weight × pdf (" << expected.x << ", "
                        << expected.y << ", " << expected.z << ")";
                    ++checked;
                }
            }
            EXPECT_GT(checked, 0) << c.name << ": no delta sample";
        }
}

// Smooth BSDFs have no delta lobe: g = 0 for any pair of directions.
TEST(BsdfDeltaWeight, ZeroWithoutDeltaLobes) {
    const SurfaceInteraction3f si = make_si(Vec3f(0.3f, 0.2f, 0.9f));
    const Vec3f mirror(-si.wi.x, -si.wi.y, si.wi.z);
    EXPECT_TRUE(is_black(make_diffuse(tex(0.5f))->delta_weight(BSDFContext{}, si, mirror)));
    // The plastic's diffuse base has no delta part below the surface.
    EXPECT_TRUE(is_black(make_plastic(1.5f, tex(0.5f), tex(0.8f), false)->delta_weight(BSDFContext{}, si, -si.wi)));
}

// The Var evaluation: the float value, and d g / d cos θ_i of central differences (the incident direction
// turning in the xz-plane), for the Fresnel-weighted lobes.
TEST(BsdfDeltaWeight, VarDerivativeFollowsTheIncidentAngle) {
    const auto g_at = [](const BSDF& b, float theta, bool transmit) {
        SurfaceInteraction3f si = make_si(Vec3f(std::sin(theta), 0.f, std::cos(theta)));
        const Vec3f wo = transmit ? Vec3f(-si.wi.x, 0.f, -si.wi.z) : Vec3f(-si.wi.x, 0.f, si.wi.z);
        return b.delta_weight(BSDFContext{}, si, wo).x;
    };
    const struct {
        const char* name;
        BSDFPtr bsdf;
        bool transmit;
    } cases[] = {{"dielectric reflection", make_dielectric(1.5f, tex(1.f), tex(1.f)), false},
                 {"dielectric refraction", make_dielectric(1.5f, tex(1.f), tex(1.f)), true},
                 {"conductor", make_conductor(tex(0.2f), tex(3.f), tex(1.f)), false},
                 {"plastic", make_plastic(1.5f, tex(0.5f), tex(1.f), false), false}};
    for (const auto& c : cases)
        for (const float theta : {0.3f, 0.9f, 1.3f}) {
            Tape& tape = Tape::current();
            tape.clear();
            const Var t = Var::parameter(theta, 0);
            SurfaceInteraction<Var> si = constant_interaction(make_si(Vec3f(0.f, 0.f, 1.f)));
            si.wi = Vec3<Var>(sin(t), Var(0.f), cos(t));
            const Vec3<Var> wo =
                c.transmit ? Vec3<Var>(-si.wi.x, Var(0.f), -si.wi.z) : Vec3<Var>(-si.wi.x, Var(0.f), si.wi.z);
            const Var g = c.bsdf->delta_weight(BSDFContext{}, si, wo).x;
            EXPECT_NEAR(g.v, g_at(*c.bsdf, theta, c.transmit), 1e-5f) << c.name;
            std::vector<float> tangent;
            const std::vector<float> direction{1.f};
            tape.forward(direction.data(), tangent);
            const float ad = g.id < 0 ? 0.f : tangent[size_t(g.id)];
            const float h = 1e-3f;
            const float fd = (g_at(*c.bsdf, theta + h, c.transmit) - g_at(*c.bsdf, theta - h, c.transmit)) / (2.f * h);
            EXPECT_NEAR(ad, fd, 2e-3f * (1.f + std::abs(fd))) << c.name << " at θ " << theta;
            tape.clear();
        }
}
