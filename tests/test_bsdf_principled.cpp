// The principled and principledthin BSDFs: chi-square sampling tests, sample weights, reciprocity, energy
// bounds, Mitsuba conventions (reductions to roughconductor / roughdielectric, eval against the documented
// formulas at fixed directions), and the loader. Their derivatives: test_bsdf_principled_diff.cpp.
#include "bsdf_chi2.h"
#include "core/fresnel.h"
#include "diff/parameters.h"
#include "scene/bsdfs/bsdfs.h"
#include "scene/scene.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>

using namespace penumbra;
using namespace penumbra::test;

namespace {

struct Case {
    std::string name;
    BSDFPtr bsdf;
    Vec3f wi;
    TransportMode mode = TransportMode::Radiance;
};

const Vec3f kOblique(0.5f, 0.2f, 0.7f), kInside(0.3f, -0.4f, -0.6f), kGrazing(0.9f, 0.1f, 0.2f);

PrincipledParams principled_base() {
    PrincipledParams p;
    p.base_color = tex(Color3f(0.8f, 0.5f, 0.3f));
    return p;
}

std::vector<Case> cases() {
    std::vector<Case> out;
    PrincipledParams p = principled_base();
    out.push_back({"principled_default", make_principled(p), kOblique});
    p.metallic = tex(1.f);
    p.roughness = tex(0.4f);
    p.anisotropic = tex(0.7f);
    out.push_back({"principled_metallic_anisotropic", make_principled(p), kOblique});
    p = principled_base();
    p.spec_trans = tex(0.8f);
    p.has_spec_trans = true;
    p.roughness = tex(0.5f);
    p.eta_given = true;
    p.eta = 1.5f;
    out.push_back({"principled_spec_trans_outside", make_principled(p), kOblique});
    out.push_back({"principled_spec_trans_inside", make_principled(p), kInside});
    out.push_back(
        {"principled_spec_trans_importance", make_principled(p), kGrazing, TransportMode::Importance});
    p = principled_base();
    p.clearcoat = tex(1.f);
    p.clearcoat_gloss = tex(0.3f);
    p.metallic = tex(0.3f);
    p.sheen = tex(0.5f);
    p.flatness = tex(0.5f);
    p.spec_tint = tex(0.5f);
    out.push_back({"principled_clearcoat_sheen", make_principled(p), kOblique});
    out.push_back({"principled_clearcoat_grazing", make_principled(p), kGrazing});
    p.spec_trans = tex(0.5f);
    p.has_spec_trans = true;
    p.spec_rate = 0.5f;
    p.clearcoat_rate = 3.f;
    p.diffuse_rate = 2.f;
    out.push_back({"principled_all_lobes_sampling_rates", make_principled(p), kOblique});
    // Mitsuba's test04_chi2_spec_trans_less_dense: eta < 1 (total internal reflection from outside).
    p = PrincipledParams();
    p.roughness = tex(0.8f);
    p.metallic = tex(0.2f);
    p.clearcoat = tex(1.f);
    p.spec_trans = tex(0.5f);
    p.has_spec_trans = true;
    p.eta_given = true;
    p.eta = 0.5f;
    out.push_back({"principled_eta_below_one", make_principled(p), normalize(Vec3f(1.f, 0.f, 1.f))});
    out.push_back({"principled_eta_below_one_inside", make_principled(p), kInside});
    PrincipledThinParams t;
    t.base_color = tex(Color3f(0.7f, 0.4f, 0.2f));
    t.spec_trans = tex(0.6f);
    t.diff_trans = tex(0.8f);
    t.roughness = tex(0.4f);
    t.anisotropic = tex(0.5f);
    t.eta = tex(1.33f);
    out.push_back({"thin_spec_and_diff_trans_front", make_principledthin(t), kOblique});
    out.push_back({"thin_spec_and_diff_trans_back", make_principledthin(t), kInside});
    t.spec_reflect_rate = 2.f;
    t.diffuse_trans_rate = 0.5f;
    out.push_back({"thin_sampling_rates", make_principledthin(t), kOblique});
    t.spec_trans = tex(1.f);
    t.roughness = tex(0.6f);
    t.anisotropic = tex(0.f);
    out.push_back({"thin_specular_only", make_principledthin(t), kGrazing});
    return out;
}

BSDFContext context(TransportMode mode) {
    BSDFContext ctx;
    ctx.mode = mode;
    return ctx;
}

} // namespace

TEST(Principled, ChiSquareSampleMatchesPdf) {
    const auto all = cases();
    // Overall significance 0.01, Sidak-corrected over the cases (a correct implementation fails with p = 1%).
    const double alpha = 1.0 - std::pow(1.0 - 0.01, 1.0 / double(all.size()));
    uint64_t seed = 101;
    for (const auto& c : all) {
        const auto r = bsdf_chi2(*c.bsdf, make_si(c.wi), context(c.mode), 400000, seed++);
        EXPECT_GT(r.p_value, alpha) << c.name << ": " << r.report;
        std::printf("  %s: %s\n", c.name.c_str(), r.report.c_str());
    }
}

TEST(Principled, SampleWeightIsEvalOverPdf) {
    for (const auto& c : cases()) {
        const auto si = make_si(c.wi);
        const BSDFContext ctx = context(c.mode);
        PCG32 rng(7);
        int checked = 0;
        for (int i = 0; i < 2000; ++i) {
            const float u1 = rng.next_float();
            const Vec2f u2(rng.next_float(), rng.next_float());
            const auto [bs, w] = c.bsdf->sample(ctx, si, u1, u2);
            if (bs.pdf == 0.f || is_black(w)) continue;
            const float pdf = c.bsdf->pdf(ctx, si, bs.wo);
            const Color3f f = c.bsdf->eval(ctx, si, bs.wo);
            // The same float expressions evaluated twice: rounding only.
            ASSERT_NEAR(bs.pdf, pdf, 1e-3f * pdf) << c.name;
            for (int k = 0; k < 3; ++k)
                ASSERT_NEAR(w[k], f[k] / pdf, 1e-3f * (f[k] / pdf) + 1e-6f) << c.name;
            ++checked;
        }
        EXPECT_GT(checked, 1000) << c.name << ": too many failed samples";
    }
}

// Both BSDFs reflect reciprocally: f(a, c) = f(c, a) (every reflection term is symmetric in wi and wo).
TEST(Principled, ReflectionIsReciprocal) {
    PCG32 rng(3);
    for (const auto& c : cases()) {
        for (int i = 0; i < 200; ++i) {
            const Vec3f a =
                normalize(Vec3f(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() + 0.05f));
            const Vec3f b =
                normalize(Vec3f(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() + 0.05f));
            const Color3f fab = c.bsdf->eval(BSDFContext(), make_si(a), b) / b.z;
            const Color3f fba = c.bsdf->eval(BSDFContext(), make_si(b), a) / a.z;
            // The same terms in a different order: float rounding only.
            for (int k = 0; k < 3; ++k)
                ASSERT_NEAR(fab[k], fba[k], 1e-4f * std::max(1.f, fab[k])) << c.name;
        }
    }
}

// All sampling rates 0 (accepted by Mitsuba): nothing is sampled and the pdf is 0, but eval still works.
TEST(Principled, ZeroSamplingRatesSampleNothing) {
    PrincipledParams p;
    p.spec_rate = p.clearcoat_rate = p.diffuse_rate = 0.f;
    const BSDFPtr bsdf = make_principled(p);
    const auto si = make_si(kOblique);
    const auto [bs, w] = bsdf->sample(BSDFContext(), si, 0.3f, Vec2f(0.4f, 0.6f));
    EXPECT_EQ(bs.pdf, 0.f);
    EXPECT_TRUE(is_black(w));
    EXPECT_EQ(bsdf->pdf(BSDFContext(), si, Vec3f(0.f, 0.f, 1.f)), 0.f);
    EXPECT_GT(bsdf->eval(BSDFContext(), si, Vec3f(0.f, 0.f, 1.f)).x, 0.f);
}

namespace {
// Monte Carlo albedo ∫ f |cos_o| dwo = E[weight] (max over channels) with its standard error.
std::pair<double, double> albedo(const BSDF& bsdf, const Vec3f& wi, int n, uint64_t seed) {
    PCG32 rng(seed);
    double sum = 0.0, sum2 = 0.0;
    const auto si = make_si(wi);
    for (int i = 0; i < n; ++i) {
        const float u1 = rng.next_float();
        const Vec2f u2(rng.next_float(), rng.next_float());
        const auto [bs, w] = bsdf.sample(context(TransportMode::Importance), si, u1, u2);
        const double v = bs.pdf > 0.f ? max_component(w) : 0.0;
        sum += v;
        sum2 += v * v;
    }
    const double mean = sum / n;
    return {mean, std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n)};
}
} // namespace

// White metals, white glass and white thin sheets reflect and transmit at most what arrives. (The Disney
// diffuse lobe is not energy conserving: with retro-reflection, and with the specular lobe added on top, the
// default material's albedo reaches ~1.4 at grazing incidence, in Mitsuba as here; it is not tested.)
TEST(Principled, EnergyConservationOfWhiteMetalGlassAndThinSheets) {
    for (float roughness : {0.1f, 0.5f, 1.f}) {
        PrincipledParams metal;
        metal.base_color = tex(1.f);
        metal.metallic = tex(1.f);
        metal.roughness = tex(roughness);
        PrincipledParams glass;
        glass.base_color = tex(1.f);
        glass.spec_trans = tex(1.f);
        glass.has_spec_trans = true;
        glass.roughness = tex(roughness);
        PrincipledThinParams thin;
        thin.base_color = tex(1.f);
        thin.spec_trans = tex(0.5f);
        thin.diff_trans = tex(1.f);
        thin.roughness = tex(roughness);
        const std::vector<std::pair<std::string, BSDFPtr>> bsdfs = {{"metal", make_principled(metal)},
                                                                    {"glass", make_principled(glass)},
                                                                    {"thin", make_principledthin(thin)}};
        for (const auto& [name, bsdf] : bsdfs)
            for (float z : {0.95f, 0.5f, 0.1f, -0.5f}) {
                const Vec3f wi(std::sqrt(1.f - z * z), 0.f, z);
                const auto [mean, err] = albedo(*bsdf, wi, 100000, 11);
                // 3 standard errors of the Monte Carlo mean, plus float rounding.
                EXPECT_LE(mean, 1.0 + 3.0 * err + 1e-5)
                    << name << " roughness " << roughness << " cos_i " << z;
            }
    }
}

namespace {
// GGX written out from Walter et al. 2007 (Eqs. 33, 34), independently of core/microfacet.h.
double ggx_D(const Vec3f& m, double ax, double ay) {
    const double r = m.x * m.x / (ax * ax) + m.y * m.y / (ay * ay) + double(m.z) * m.z;
    return 1.0 / (Pi * ax * ay * r * r);
}
double ggx_G1(const Vec3f& v, const Vec3f& m, double ax, double ay) {
    if (dot(v, m) * v.z <= 0.f) return 0.0;
    const double tan2 = (ax * ax * v.x * v.x + ay * ay * v.y * v.y) / (double(v.z) * v.z);
    return 2.0 / (1.0 + std::sqrt(1.0 + tan2));
}
double schlick(double r0, double c) { return r0 + (1.0 - r0) * std::pow(1.0 - c, 5.0); }

struct Directions {
    Vec3f wi, wo;
};
const Directions kPairs[] = {{Vec3f(0.5f, 0.2f, 0.7f), Vec3f(-0.3f, 0.1f, 0.8f)},
                             {Vec3f(0.1f, -0.6f, 0.4f), Vec3f(0.2f, 0.7f, 0.5f)},
                             {Vec3f(0.8f, 0.f, 0.3f), Vec3f(-0.7f, 0.2f, 0.4f)},
                             {Vec3f(0.f, 0.f, 1.f), Vec3f(0.6f, 0.f, 0.8f)}};

Color3f eval_at(const BSDF& bsdf, const Vec3f& wi, const Vec3f& wo) {
    return bsdf.eval(BSDFContext(), make_si(wi), normalize(wo));
}
void expect_color_near(const Color3f& got, const Color3f& want, const std::string& what) {
    for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(got[k], want[k], 1e-4f * std::max(1.f, std::abs(want[k]))) << what << " channel " << k;
}
} // namespace

// Mitsuba: metallic = 1 is a GGX conductor with Schlick's Fresnel at base_color, α = roughness² (stretched by
// aspect = sqrt(1 − 0.9 anisotropic)); with a white base it is exactly roughconductor's perfect mirror.
TEST(Principled, MetallicIsASchlickGGXConductorWithAlphaRoughnessSquared) {
    const float roughness = 0.6f, anisotropic = 0.5f;
    const double aspect = std::sqrt(1.0 - 0.9 * anisotropic);
    const double ax = roughness * roughness / aspect, ay = roughness * roughness * aspect;
    PrincipledParams p;
    p.metallic = tex(1.f);
    p.roughness = tex(roughness);
    p.anisotropic = tex(anisotropic);
    p.base_color = tex(Color3f(0.9f, 0.6f, 0.2f));
    const BSDFPtr metal = make_principled(p);
    p.base_color = tex(1.f);
    const BSDFPtr white = make_principled(p);
    RoughnessParams r;
    r.type = MicrofacetType::GGX;
    r.alpha_u = tex(float(ax));
    r.alpha_v = tex(float(ay));
    const BSDFPtr mirror = make_roughconductor(r, tex(0.f), tex(1.f), tex(1.f));
    for (const auto& d : kPairs) {
        const Vec3f wi = normalize(d.wi), wo = normalize(d.wo), h = normalize(wi + wo);
        const double c = dot(wi, h);
        const double common = ggx_D(h, ax, ay) * ggx_G1(wi, h, ax, ay) * ggx_G1(wo, h, ax, ay) / (4.0 * wi.z);
        const Color3f want(float(schlick(0.9, c) * common), float(schlick(0.6, c) * common),
                           float(schlick(0.2, c) * common));
        expect_color_near(eval_at(*metal, wi, wo), want, "metallic eval");
        expect_color_near(eval_at(*white, wi, wo), eval_at(*mirror, wi, wo), "white metal vs roughconductor");
        EXPECT_NEAR(white->pdf(BSDFContext(), make_si(wi), wo), mirror->pdf(BSDFContext(), make_si(wi), wo),
                    1e-4f * mirror->pdf(BSDFContext(), make_si(wi), wo));
    }
}

// Mitsuba: spec_trans = 1 with a white base, no tint and an explicit eta is roughdielectric (GGX, α =
// roughness²) on both sides, in eval and in pdf (reflection chosen with probability F).
TEST(Principled, SpecTransIsARoughDielectric) {
    const float roughness = 0.5f, eta = 1.45f;
    PrincipledParams p;
    p.base_color = tex(1.f);
    p.spec_trans = tex(1.f);
    p.has_spec_trans = true;
    p.roughness = tex(roughness);
    p.eta_given = true;
    p.eta = eta;
    const BSDFPtr glass = make_principled(p);
    RoughnessParams r;
    r.type = MicrofacetType::GGX;
    r.alpha_u = r.alpha_v = tex(roughness * roughness);
    const BSDFPtr reference = make_roughdielectric(r, eta, tex(1.f), tex(1.f));
    PCG32 rng(17);
    int nonzero = 0;
    for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance})
        for (int i = 0; i < 400; ++i) {
            const Vec3f wi =
                normalize(Vec3f(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f));
            const Vec3f wo =
                normalize(Vec3f(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f));
            const auto si = make_si(wi);
            const Color3f a = glass->eval(context(mode), si, wo), b = reference->eval(context(mode), si, wo);
            expect_color_near(a, b, "eval");
            const float pa = glass->pdf(context(mode), si, wo), pb = reference->pdf(context(mode), si, wo);
            EXPECT_NEAR(pa, pb, 1e-4f * std::max(1.f, pb));
            nonzero += pb > 0.f;
        }
    EXPECT_GT(nonzero, 400);
}

// The diffuse lobe against Burley 2012 (and the BRDF explorer's disney.brdf), with F = 0 (specular = 0
// gives eta = 1): base/π (1 + (F_D90 − 1) F_i)(1 + (F_D90 − 1) F_o), F_D90 = 0.5 + 2 roughness cos²θ_d;
// flatness = 1: base/π 1.25 (F_ss (1 / (cos_i + cos_o) − 0.5) + 0.5), F_ss90 = roughness cos²θ_d; sheen with
// a black base: sheen (1 − cos θ_d)^5. Each times cos_o.
TEST(Principled, DiffuseFlatnessAndSheenMatchBurley) {
    const float roughness = 0.7f;
    PrincipledParams p;
    p.specular = 0.f;
    p.roughness = tex(roughness);
    p.base_color = tex(Color3f(0.8f, 0.4f, 0.1f));
    const BSDFPtr diffuse = make_principled(p);
    p.flatness = tex(1.f);
    const BSDFPtr flat = make_principled(p);
    p.flatness = tex(0.f);
    p.base_color = tex(0.f);
    p.sheen = tex(0.6f);
    const BSDFPtr sheen = make_principled(p);
    for (const auto& d : kPairs) {
        const Vec3f wi = normalize(d.wi), wo = normalize(d.wo), h = normalize(wi + wo);
        const double cd = dot(wo, h), fi = std::pow(1.0 - wi.z, 5.0), fo = std::pow(1.0 - wo.z, 5.0);
        const double fd90 = 0.5 + 2.0 * roughness * cd * cd;
        const double burley = (1.0 + (fd90 - 1.0) * fi) * (1.0 + (fd90 - 1.0) * fo) * wo.z / Pi;
        expect_color_near(eval_at(*diffuse, wi, wo), Color3f(0.8f, 0.4f, 0.1f) * float(burley), "diffuse");
        const double fss90 = roughness * cd * cd;
        const double fss = (1.0 + (fss90 - 1.0) * fi) * (1.0 + (fss90 - 1.0) * fo);
        const double ss = 1.25 * (fss * (1.0 / (wi.z + wo.z) - 0.5) + 0.5) * wo.z / Pi;
        expect_color_near(eval_at(*flat, wi, wo), Color3f(0.8f, 0.4f, 0.1f) * float(ss), "fake subsurface");
        expect_color_near(eval_at(*sheen, wi, wo), Color3f(float(0.6 * std::pow(1.0 - cd, 5.0) * wo.z)),
                          "sheen");
    }
}

// Mitsuba's clearcoat: clearcoat/4 · Schlick(0.04, wi·h) · GTR1_α(h) · G1_0.25(wi) G1_0.25(wo) · cos_o, α =
// lerp(0.1, 0.001, clearcoat_gloss), GTR1_α(h) = (α² − 1) / (π ln α² (1 + (α² − 1) cos²θ_h)). (Unlike
// Burley's BRDF explorer, Mitsuba applies no 1 / (4 cos_i cos_o) here; penumbra follows Mitsuba.)
TEST(Principled, ClearcoatMatchesMitsubasGTR1Lobe) {
    const float gloss = 0.4f, clearcoat = 0.8f;
    PrincipledParams p;
    p.specular = 0.f;
    p.base_color = tex(0.f);
    p.clearcoat = tex(clearcoat);
    p.clearcoat_gloss = tex(gloss);
    const BSDFPtr coat = make_principled(p);
    const double a2 = std::pow(0.1 * (1.0 - gloss) + 0.001 * gloss, 2.0);
    for (const auto& d : kPairs) {
        const Vec3f wi = normalize(d.wi), wo = normalize(d.wo), h = normalize(wi + wo);
        const double D = (a2 - 1.0) / (Pi * std::log(a2) * (1.0 + (a2 - 1.0) * h.z * h.z));
        const double G = ggx_G1(wi, h, 0.25, 0.25) * ggx_G1(wo, h, 0.25, 0.25);
        const double want = 0.25 * clearcoat * schlick(0.04, dot(wi, h)) * D * G * wo.z;
        expect_color_near(eval_at(*coat, wi, wo), Color3f(float(want)), "clearcoat");
    }
}

// principledthin: the specular reflection F D G / (4 cos_i) (α = roughness²), the transmission base (1 − F)
// D' G' / (4 cos_i) towards the mirrored direction with roughness scaled by 0.65 eta − 0.35, and the
// Lambertian transmission base/π cos_o for diff_trans = 2; the same seen from the back side.
TEST(Principled, ThinLobesMatchTheirFormulas) {
    const float roughness = 0.5f, eta = 1.4f;
    PrincipledThinParams t;
    t.roughness = tex(roughness);
    t.eta = tex(eta);
    t.base_color = tex(Color3f(0.9f, 0.5f, 0.3f));
    t.spec_trans = tex(1.f);
    const BSDFPtr specular = make_principledthin(t);
    t.spec_trans = tex(0.f);
    t.diff_trans = tex(2.f);
    const BSDFPtr lambert = make_principledthin(t);
    const double a = roughness * roughness, rs = (0.65 * eta - 0.35) * roughness, at = rs * rs;
    for (const auto& d : kPairs)
        for (float side : {1.f, -1.f}) {
            const Vec3f wi = normalize(d.wi), wo = normalize(d.wo), h = normalize(wi + wo);
            const Vec3f wt(wo.x, wo.y, -wo.z); // through the sheet
            const double F = fresnel_dielectric(dot(wi, h), eta).F;
            const double refl = F * ggx_D(h, a, a) * ggx_G1(wi, h, a, a) * ggx_G1(wo, h, a, a) / (4.0 * wi.z);
            const double trans =
                (1.0 - F) * ggx_D(h, at, at) * ggx_G1(wi, h, at, at) * ggx_G1(wt, h, at, at) / (4.0 * wi.z);
            const Vec3f si_wi = wi * side;
            expect_color_near(eval_at(*specular, si_wi, wo * side), Color3f(float(refl)), "thin reflection");
            expect_color_near(eval_at(*specular, si_wi, wt * side), Color3f(0.9f, 0.5f, 0.3f) * float(trans),
                              "thin transmission");
            expect_color_near(eval_at(*lambert, si_wi, wt * side),
                              Color3f(0.9f, 0.5f, 0.3f) * float(wo.z / Pi), "diffuse transmission");
            expect_color_near(eval_at(*lambert, si_wi, wo * side), Color3f(0.f), "no diffuse reflection");
        }
}

namespace {
// pdf and eval (first channel) along wo = (sin θ, 0, cos θ), θ = i/19 · π/2, for wi = (1, 0, 1) (not
// normalized), as Mitsuba 3's own regression tests pin them (src/bsdfs/tests/test_principled.py and
// test_principledthin.py, test05_eval_pdf / test03_eval_pdf_thin, scalar_rgb).
void expect_mitsuba_values(const BSDF& bsdf, const double (&pdf_true)[20], const double (&eval_true)[20]) {
    SurfaceInteraction3f si;
    si.wi = Vec3f(1.f, 0.f, 1.f);
    for (int i = 0; i < 20; ++i) {
        const double theta = i / 19.0 * (std::acos(-1.0) / 2.0); // in double, as in the Python test
        const Vec3f wo(float(std::sin(theta)), 0.f, float(std::cos(theta)));
        // Mitsuba's own criterion (dr.allclose: relative 1e-5, absolute 1e-8).
        EXPECT_NEAR(bsdf.pdf(BSDFContext(), si, wo), pdf_true[i], 1e-5 * pdf_true[i] + 1e-8)
            << "pdf, i = " << i;
        EXPECT_NEAR(bsdf.eval(BSDFContext(), si, wo).x, eval_true[i], 1e-5 * eval_true[i] + 1e-8)
            << "eval, i = " << i;
    }
}
} // namespace

TEST(Principled, EvalAndPdfMatchMitsubasRegressionValues) {
    PrincipledParams p;
    p.metallic = tex(0.3f);
    p.spec_tint = tex(0.6f);
    p.specular = 0.4f;
    p.anisotropic = tex(0.3f);
    p.clearcoat = tex(0.3f);
    p.clearcoat_gloss = tex(0.5f);
    p.sheen = tex(0.9f);
    p.sheen_tint = tex(0.9f);
    p.spec_trans = tex(0.5f);
    p.has_spec_trans = true;
    p.flatness = tex(0.5f);
    const double pdf_true[20] = {
        0.17007458209991455,  0.15398569405078888,  0.14061447978019714,  0.12924496829509735,
        0.1193309798836708,   0.1104581207036972,   0.10231398791074753,  0.09466464817523956,
        0.08733665198087692,  0.08020336925983429,  0.07317451387643814,  0.06618815660476685,
        0.0592045858502388,   0.052201706916093826, 0.045171335339546204, 0.03811638057231903,
        0.031048627570271492, 0.02398696169257164,  0.016955917701125145, 0.009984553791582584};
    const double eval_true[20] = {
        0.06804995983839035,  0.06425636261701584,  0.060901228338479996, 0.057847555726766586,
        0.05498623475432396,  0.05223095044493675,  0.049513764679431915, 0.04678140580654144,
        0.04399249702692032,  0.04111534729599953,  0.03812596574425697,  0.03500543162226677,
        0.031735487282276154, 0.02829158864915371,  0.024633212015032768, 0.02069348469376564,
        0.01637275144457817,  0.011544802226126194, 0.006091561634093523, 4.703659982886835e-18};
    expect_mitsuba_values(*make_principled(p), pdf_true, eval_true);
}

TEST(Principled, ThinEvalAndPdfMatchMitsubasRegressionValues) {
    PrincipledThinParams t;
    t.eta = tex(1.5f);
    t.anisotropic = tex(0.5f);
    t.sheen = tex(0.5f);
    t.sheen_tint = tex(0.2f);
    t.spec_trans = tex(0.5f);
    t.has_spec_trans = true;
    t.flatness = tex(0.5f);
    t.diff_trans = tex(0.6f);
    const double pdf_true[20] = {
        0.18230389058589935, 0.17071931064128876,  0.1604636013507843,  0.15113641321659088,
        0.1424213945865631,  0.13407252728939056,  0.1259022206068039,  0.1177704930305481,
        0.10957615822553635, 0.1012495756149292,   0.09274674206972122, 0.0840444564819336,
        0.07513649761676788, 0.06603056192398071,  0.05674567073583603, 0.04731012135744095,
        0.03775978833436966, 0.028136683627963066, 0.01848774217069149, 0.008863822557032108};
    const double eval_true[20] = {
        0.04944333806633949,  0.04872140288352966,  0.047846242785453796, 0.0468028225004673,
        0.04557877406477928,  0.04416417330503464,  0.042551249265670776, 0.04073421657085419,
        0.03870923072099686,  0.036474503576755524, 0.03403010591864586,  0.0313769206404686,
        0.028513599187135696, 0.025431113317608833, 0.02210502326488495,  0.01848825439810753,
        0.014510626904666424, 0.01009628176689148,  0.005216196645051241, 3.899415020768372e-18};
    expect_mitsuba_values(*make_principledthin(t), pdf_true, eval_true);
}

namespace {
std::string bsdf_scene(const std::string& bsdf) {
    return R"(<scene version="3.0.0"><shape type="rectangle" id="plane">)" + bsdf + R"(</shape></scene>)";
}
std::string load_error(const std::string& xml) {
    try {
        load_scene_string(xml);
    } catch (const LoadError& e) {
        return e.what();
    }
    return "(no LoadError)";
}
std::vector<std::string> parameter_names(const std::string& xml) {
    auto scene = load_scene_string(xml);
    Parameters params(*scene);
    std::vector<std::string> names;
    for (const Parameter& p : params.all())
        names.push_back(p.name);
    return names;
}
bool contains(const std::vector<std::string>& v, const std::string& s) {
    return std::find(v.begin(), v.end(), s) != v.end();
}
} // namespace

// Mitsuba's parameter names load (textures where Mitsuba takes textures), traverse() uses Mitsuba's keys,
// and bad input is one clear LoadError.
TEST(Principled, LoaderAcceptsMitsubasParametersAndRejectsBadOnes) {
    const std::string all = R"(<bsdf type="principled" id="mat"><rgb name="base_color" value="1,0.5,0.2"/>
        <float name="metallic" value="0.7"/><float name="specular" value="0.6"/><float name="roughness" value="0.2"/>
        <float name="spec_tint" value="0.4"/><float name="anisotropic" value="0.5"/><float name="sheen" value="0.3"/>
        <float name="sheen_tint" value="0.2"/><float name="clearcoat" value="0.6"/><float name="clearcoat_gloss" value="0.3"/>
        <float name="spec_trans" value="0.4"/><float name="flatness" value="0.1"/>
        <float name="main_specular_sampling_rate" value="1"/><float name="clearcoat_sampling_rate" value="0.5"/>
        <float name="diffuse_reflectance_sampling_rate" value="1"/></bsdf>)";
    const auto names = parameter_names(bsdf_scene(all));
    // Textured parameters are named by their constant texture's key, `value` (Mitsuba's `base_color.value`);
    // `specular` and `eta` of principled are plain floats.
    for (const char* key : {"mat.base_color.value", "mat.roughness.value", "mat.metallic.value", "mat.specular",
                            "mat.spec_tint.value", "mat.anisotropic.value", "mat.sheen.value",
                            "mat.sheen_tint.value", "mat.clearcoat.value", "mat.clearcoat_gloss.value",
                            "mat.spec_trans.value", "mat.flatness.value"})
        EXPECT_TRUE(contains(names, key)) << key;
    EXPECT_FALSE(contains(names, "mat.eta"));
    EXPECT_TRUE(contains(parameter_names(bsdf_scene(
                             R"(<bsdf type="principled" id="mat"><float name="eta" value="1.4"/></bsdf>)")),
                         "mat.eta"));
    const std::string thin =
        R"(<bsdf type="principledthin" id="mat"><rgb name="base_color" value="0.7,0.1,0.1"/>
        <float name="roughness" value="0.15"/><float name="spec_tint" value="0.1"/><float name="anisotropic" value="0.5"/>
        <float name="spec_trans" value="0.8"/><float name="diff_trans" value="0.3"/><float name="eta" value="1.33"/>
        <float name="sheen" value="0.1"/><float name="sheen_tint" value="0.1"/><float name="flatness" value="0.2"/>
        <float name="specular_reflectance_sampling_rate" value="1"/><float name="specular_transmittance_sampling_rate" value="1"/>
        <float name="diffuse_reflectance_sampling_rate" value="1"/><float name="diffuse_transmittance_sampling_rate" value="1"/></bsdf>)";
    const auto thin_names = parameter_names(bsdf_scene(thin));
    for (const char* key : {"mat.eta.value", "mat.diff_trans.value", "mat.base_color.value", "mat.roughness.value",
                            "mat.spec_trans.value"})
        EXPECT_TRUE(contains(thin_names, key)) << key;
    // A texture where Mitsuba takes one.
    EXPECT_NO_THROW(load_scene_string(
        bsdf_scene(R"(<bsdf type="principled"><texture name="roughness" type="checkerboard"/></bsdf>)")));

    const std::string both = load_error(bsdf_scene(R"(<bsdf type="principled"><float name="eta" value="1.4"/>
        <float name="specular" value="0.5"/></bsdf>)"));
    EXPECT_NE(both.find("either \"eta\" or \"specular\""), std::string::npos) << both;
    EXPECT_NE(both.find(":2:"), std::string::npos) << both;
    EXPECT_NE(load_error(bsdf_scene(R"(<bsdf type="principled"><float name="specular" value="-1"/></bsdf>)"))
                  .find("specular"),
              std::string::npos);
    const std::string unknown =
        load_error(bsdf_scene(R"(<bsdf type="principledthin"><float name="metallic" value="1"/></bsdf>)"));
    EXPECT_NE(unknown.find("metallic"), std::string::npos) << unknown;
}

// Mitsuba's IOR conventions: specular = 0.5 is eta = 1.5 (eta = 2 / (1 − sqrt(0.08 specular)) − 1), and with
// spec_trans given, eta = 1 becomes 1.001 and specular = 0 becomes 1e-3 (an index-matched interface cannot
// transmit).
TEST(Principled, SpecularMapsToEtaAsInMitsuba) {
    PrincipledParams p;
    p.spec_trans = tex(0.7f);
    p.has_spec_trans = true;
    p.specular = 0.5f;
    const BSDFPtr by_specular = make_principled(p);
    p.eta_given = true;
    p.eta = 1.5f;
    const BSDFPtr by_eta = make_principled(p);
    for (const auto& d : kPairs)
        for (float side : {1.f, -1.f}) {
            const Vec3f wi = normalize(d.wi) * side, wo = normalize(d.wo);
            expect_color_near(eval_at(*by_specular, wi, wo), eval_at(*by_eta, wi, wo),
                              "specular 0.5 vs eta 1.5");
            const Vec3f wt(wo.x, wo.y, -wo.z);
            expect_color_near(eval_at(*by_specular, wi, wt), eval_at(*by_eta, wi, wt), "transmission");
        }
    const auto value_of = [](const std::string& xml, const std::string& name) {
        auto scene = load_scene_string(xml);
        Parameters params(*scene);
        return *params.find(name).data;
    };
    const std::string st = R"(<float name="spec_trans" value="0.5"/>)";
    EXPECT_EQ(value_of(bsdf_scene(R"(<bsdf type="principled" id="mat"><float name="eta" value="1"/>)" + st +
                                  "</bsdf>"),
                       "mat.eta"),
              1.001f);
    EXPECT_EQ(value_of(bsdf_scene(R"(<bsdf type="principled" id="mat"><float name="specular" value="0"/>)" +
                                  st + "</bsdf>"),
                       "mat.specular"),
              1e-3f);
    EXPECT_EQ(value_of(bsdf_scene(R"(<bsdf type="principled" id="mat"><float name="eta" value="1"/></bsdf>)"),
                       "mat.eta"),
              1.f);
}

// Mitsuba BSDFs left out on purpose name themselves and the reason, on one line.
TEST(Principled, OutOfScopeBSDFsSayWhy) {
    for (const char* type : {"polarizer", "retarder", "circular", "pplastic", "measured_polarized"}) {
        const std::string e = load_error(bsdf_scene("<bsdf type=\"" + std::string(type) + "\"/>"));
        EXPECT_NE(e.find("unsupported bsdf plugin '" + std::string(type) + "': "), std::string::npos) << e;
        EXPECT_NE(e.find("unpolarized"), std::string::npos) << e;
        EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    }
    const std::string hair = load_error(bsdf_scene(R"(<bsdf type="hair"/>)"));
    EXPECT_NE(hair.find("unsupported bsdf plugin 'hair': "), std::string::npos) << hair;
    EXPECT_NE(hair.find("curve"), std::string::npos) << hair;
    EXPECT_NE(load_error(bsdf_scene(R"(<bsdf type="measured"/>)")).find("measured BRDFs"), std::string::npos);
    EXPECT_NE(
        load_error(bsdf_scene(R"(<bsdf type="nosuchbsdf"/>)")).find("unsupported bsdf plugin 'nosuchbsdf'"),
        std::string::npos);
}
