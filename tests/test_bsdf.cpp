// BSDF tests: chi-square sampling tests, sample weights, reciprocity, energy and Fresnel/Snell checks.
#include "bsdf_chi2.h"
#include "core/fresnel.h"
#include "scene/bsdfs/bsdfs.h"
#include "scene/properties.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>

using namespace penumbra;
using namespace penumbra::test;

namespace {

RoughnessParams rough(MicrofacetType type, float au, float av, bool visible = true) {
    RoughnessParams r;
    r.type = type;
    r.alpha_u = tex(au);
    r.alpha_v = tex(av);
    r.sample_visible = visible;
    return r;
}
constexpr auto Beckmann = MicrofacetType::Beckmann;
constexpr auto GGX = MicrofacetType::GGX;

struct Case {
    std::string name;
    BSDFPtr bsdf;
    Vec3f wi;
    TransportMode mode = TransportMode::Radiance;
};

BSDFPtr mirror_conductor(const RoughnessParams& r) { return make_roughconductor(r, tex(0.f), tex(1.f), tex(1.f)); }

std::vector<Case> smooth_cases() {
    const Vec3f oblique(0.5f, 0.2f, 0.7f), inside(0.3f, -0.4f, -0.6f);
    return {
        {"diffuse", make_diffuse(tex(0.5f)), oblique},
        {"roughconductor_beckmann", make_roughconductor(rough(Beckmann, 0.3f, 0.3f), tex(0.2f), tex(3.f), tex(1.f)), oblique},
        {"roughconductor_ggx_aniso", mirror_conductor(rough(GGX, 0.2f, 0.5f)), oblique},
        {"roughconductor_beckmann_aniso", mirror_conductor(rough(Beckmann, 0.5f, 0.2f)), oblique},
        {"roughconductor_ggx_allnormals", mirror_conductor(rough(GGX, 0.3f, 0.3f, false)), oblique},
        {"roughconductor_beckmann_grazing", mirror_conductor(rough(Beckmann, 0.4f, 0.4f)), Vec3f(0.9f, 0.f, 0.15f)},
        {"roughdielectric_beckmann_outside", make_roughdielectric(rough(Beckmann, 0.3f, 0.3f), 1.5f, tex(1.f), tex(1.f)), oblique},
        {"roughdielectric_ggx_inside", make_roughdielectric(rough(GGX, 0.3f, 0.3f), 1.5f, tex(1.f), tex(1.f)), inside},
        {"roughdielectric_ggx_aniso_importance", make_roughdielectric(rough(GGX, 0.2f, 0.4f), 1.33f, tex(1.f), tex(1.f)),
         oblique, TransportMode::Importance},
        {"roughdielectric_beckmann_allnormals_inside",
         make_roughdielectric(rough(Beckmann, 0.3f, 0.3f, false), 1.5f, tex(1.f), tex(1.f)), inside},
        {"plastic", make_plastic(1.49f, tex(0.5f), tex(1.f), false), oblique},
        {"roughplastic_beckmann", make_roughplastic(Beckmann, 0.3f, true, 1.49f, tex(0.5f), tex(1.f), false), oblique},
        {"roughplastic_ggx_nonlinear", make_roughplastic(GGX, 0.2f, true, 1.5f, tex(Color3f(0.2f, 0.5f, 0.8f)), tex(1.f), true),
         oblique},
        {"blend_diffuse_roughconductor",
         make_blendbsdf(tex(0.3f), make_diffuse(tex(0.5f)), mirror_conductor(rough(GGX, 0.3f, 0.3f))), oblique},
        {"blend_plastic_diffuse", make_blendbsdf(tex(0.6f), make_plastic(1.5f, tex(0.5f), tex(1.f), false),
                                                 make_diffuse(tex(0.8f))), oblique},
        {"mask_roughconductor", make_mask(tex(0.7f), mirror_conductor(rough(Beckmann, 0.3f, 0.3f))), oblique},
        {"twosided_back", make_twosided(mirror_conductor(rough(GGX, 0.3f, 0.3f)), make_diffuse(tex(0.5f))), inside},
        // A normal tilted ~35 degrees (samples leaving the original hemisphere are rejected, as Mitsuba does).
        {"normalmap_roughconductor_aniso",
         make_normalmap(tex(Color3f(0.8f, 0.4f, 0.9f)), mirror_conductor(rough(GGX, 0.2f, 0.5f))), oblique},
        {"normalmap_diffuse", make_normalmap(tex(Color3f(0.2f, 0.6f, 0.9f)), make_diffuse(tex(0.5f))), oblique},
    };
}

BSDFContext context(TransportMode mode) {
    BSDFContext ctx;
    ctx.mode = mode;
    return ctx;
}

} // namespace

TEST(BSDF, ChiSquareSampleMatchesPdf) {
    const auto cases = smooth_cases();
    // Overall significance 0.01, Sidak-corrected over the cases so that a correct implementation fails
    // this test with probability 1%.
    const double alpha = 1.0 - std::pow(1.0 - 0.01, 1.0 / double(cases.size()));
    uint64_t seed = 1;
    for (const auto& c : cases) {
        const auto r = bsdf_chi2(*c.bsdf, make_si(c.wi), context(c.mode), 400000, seed++);
        EXPECT_GT(r.p_value, alpha) << c.name << ": " << r.report;
        if (std::getenv("PENUMBRA_VERBOSE")) std::printf("%s: %s\n", c.name.c_str(), r.report.c_str());
    }
}

namespace {
// Negative control for the chi-square helper: samples one BSDF but reports another's pdf.
class MismatchedBSDF final : public BSDFBase<MismatchedBSDF> {
public:
    MismatchedBSDF(BSDFPtr sampler, BSDFPtr density) : sampler_(std::move(sampler)), density_(std::move(density)) {}
    template <typename T> Color3<T> eval_t(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        return density_->eval(ctx, si, wo);
    }
    template <typename T> T pdf_t(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        return density_->pdf(ctx, si, wo);
    }
    std::pair<BSDFSample, Color3f> sample(const BSDFContext& ctx, const SurfaceInteraction3f& si, float u1,
                                          const Vec2f& u2) const override {
        return sampler_->sample(ctx, si, u1, u2);
    }

private:
    BSDFPtr sampler_, density_;
};
} // namespace

TEST(BSDF, ChiSquareDetectsWrongPdf) {
    // A 10% roughness error and a GGX/Beckmann swap must both be rejected at the significance used above.
    const MismatchedBSDF rough_err(mirror_conductor(rough(GGX, 0.3f, 0.3f)), mirror_conductor(rough(GGX, 0.33f, 0.33f)));
    const MismatchedBSDF dist_err(mirror_conductor(rough(GGX, 0.3f, 0.3f)), mirror_conductor(rough(Beckmann, 0.3f, 0.3f)));
    const auto si = make_si(Vec3f(0.5f, 0.2f, 0.7f));
    EXPECT_LT(bsdf_chi2(rough_err, si, BSDFContext(), 400000, 99).p_value, 1e-4);
    EXPECT_LT(bsdf_chi2(dist_err, si, BSDFContext(), 400000, 98).p_value, 1e-4);
}

TEST(BSDF, SampleWeightIsEvalOverPdf) {
    for (const auto& c : smooth_cases()) {
        const auto si = make_si(c.wi);
        const BSDFContext ctx = context(c.mode);
        PCG32 rng(7);
        int checked = 0;
        for (int i = 0; i < 2000; ++i) {
            const float u1 = rng.next_float();
            const Vec2f u2(rng.next_float(), rng.next_float());
            const auto [bs, w] = c.bsdf->sample(ctx, si, u1, u2);
            if (bs.pdf == 0.f || is_black(w) || (bs.sampled_type & BSDFDelta)) continue;
            const float pdf = c.bsdf->pdf(ctx, si, bs.wo);
            const Color3f f = c.bsdf->eval(ctx, si, bs.wo);
            // Same float expressions evaluated twice: only rounding differences (relative 1e-3 is generous).
            ASSERT_NEAR(bs.pdf, pdf, 1e-3f * pdf) << c.name;
            for (int k = 0; k < 3; ++k) ASSERT_NEAR(w[k], f[k] / pdf, 1e-3f * (f[k] / pdf) + 1e-6f) << c.name;
            ++checked;
        }
        EXPECT_GT(checked, 100) << c.name << ": too few non-delta samples";
    }
}

TEST(BSDF, ReflectionIsReciprocal) {
    const std::vector<BSDFPtr> bsdfs = {
        make_diffuse(tex(0.5f)),
        make_roughconductor(rough(Beckmann, 0.3f, 0.3f), tex(0.2f), tex(3.f), tex(1.f)),
        mirror_conductor(rough(GGX, 0.2f, 0.5f)),
        make_roughdielectric(rough(GGX, 0.3f, 0.3f), 1.5f, tex(1.f), tex(1.f)),
        make_plastic(1.49f, tex(0.5f), tex(1.f), false),
        make_roughplastic(Beckmann, 0.3f, true, 1.49f, tex(0.5f), tex(1.f), false),
    };
    PCG32 rng(3);
    const BSDFContext ctx;
    for (size_t b = 0; b < bsdfs.size(); ++b)
        for (int i = 0; i < 200; ++i) {
            const Vec3f a = normalize(Vec3f(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() + 0.05f));
            const Vec3f c = normalize(Vec3f(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() + 0.05f));
            const Color3f fab = bsdfs[b]->eval(ctx, make_si(a), c) / c.z;
            const Color3f fba = bsdfs[b]->eval(ctx, make_si(c), a) / a.z;
            // f(a, c) and f(c, a) use the same terms in a different order: float rounding only.
            for (int k = 0; k < 3; ++k) ASSERT_NEAR(fab[k], fba[k], 1e-4f * std::max(1.f, fab[k])) << "bsdf " << b;
        }
}

namespace {
// Monte Carlo albedo int f |cos_o| dwo = E[weight] with its standard error (max over channels).
std::pair<double, double> albedo(const BSDF& bsdf, const Vec3f& wi, TransportMode mode, int n, uint64_t seed) {
    PCG32 rng(seed);
    double sum = 0.0, sum2 = 0.0;
    const auto si = make_si(wi);
    for (int i = 0; i < n; ++i) {
        const float u1 = rng.next_float();
        const Vec2f u2(rng.next_float(), rng.next_float());
        const auto [bs, w] = bsdf.sample(context(mode), si, u1, u2);
        const double v = bs.pdf > 0.f ? max_component(w) : 0.0;
        sum += v;
        sum2 += v * v;
    }
    const double mean = sum / n;
    return {mean, std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n)};
}
} // namespace

TEST(BSDF, EnergyConservation) {
    const std::vector<std::pair<std::string, BSDFPtr>> bsdfs = {
        {"roughconductor_beckmann", mirror_conductor(rough(Beckmann, 0.5f, 0.5f))},
        {"roughconductor_ggx_aniso", mirror_conductor(rough(GGX, 0.8f, 0.2f))},
        {"roughdielectric_importance", make_roughdielectric(rough(GGX, 0.5f, 0.5f), 1.5f, tex(1.f), tex(1.f))},
        {"roughplastic", make_roughplastic(GGX, 0.3f, true, 1.5f, tex(1.f), tex(1.f), false)},
        {"plastic", make_plastic(1.5f, tex(1.f), tex(1.f), false)},
        {"dielectric", make_dielectric(1.5f, tex(1.f), tex(1.f))},
        {"conductor", make_conductor(tex(0.f), tex(1.f), tex(1.f))},
    };
    for (const auto& [name, bsdf] : bsdfs)
        for (float z : {0.95f, 0.5f, 0.1f}) {
            const Vec3f wi(std::sqrt(1.f - z * z), 0.f, z);
            // Importance mode: no 1/eta^2 radiance scaling, so energy conservation means albedo <= 1.
            const auto [mean, err] = albedo(*bsdf, wi, TransportMode::Importance, 100000, 11);
            // 3 standard errors of the Monte Carlo mean, plus float rounding.
            EXPECT_LE(mean, 1.0 + 3.0 * err + 1e-5) << name << " cos_i " << z;
        }
    // A perfect mirror (material "none": eta 0, k 1) reflects everything.
    const auto [m, e] = albedo(*make_conductor(tex(0.f), tex(1.f), tex(1.f)), Vec3f(0.6f, 0.f, 0.8f),
                               TransportMode::Radiance, 1000, 1);
    EXPECT_NEAR(m, 1.0, 1e-5) << e;
}

TEST(BSDF, DiffuseAlbedoEqualsReflectance) {
    const auto bsdf = make_diffuse(tex(0.7f));
    // Estimate int f cos dwo with uniform hemisphere sampling (not the BSDF's own sampler).
    PCG32 rng(5);
    const auto si = make_si(Vec3f(0.3f, 0.1f, 0.8f));
    const int n = 200000;
    double sum = 0, sum2 = 0;
    for (int i = 0; i < n; ++i) {
        const float z = rng.next_float(), phi = 2.f * Pi * rng.next_float();
        const float r = std::sqrt(1.f - z * z);
        const double v = bsdf->eval(BSDFContext(), si, Vec3f(r * std::cos(phi), r * std::sin(phi), z)).x * 2.0 * Pi;
        sum += v;
        sum2 += v * v;
    }
    const double mean = sum / n, err = std::sqrt((sum2 / n - mean * mean) / n);
    EXPECT_NEAR(mean, 0.7, 3.0 * err); // 3 standard errors
}

TEST(BSDF, DielectricFresnelAndSnell) {
    const float eta = 1.5f;
    for (float ci : {1.f, 0.8f, 0.4f, 0.05f, -0.9f, -0.5f, -0.2f}) {
        const auto fr = fresnel_dielectric(ci, eta);
        const Vec3f wi(std::sqrt(1.f - ci * ci), 0.f, ci);
        const auto bsdf = make_dielectric(eta, tex(1.f), tex(1.f));
        const auto si = make_si(wi);
        BSDFContext ctx;
        ctx.mode = TransportMode::Importance;
        const auto [bs_r, w_r] = bsdf->sample(ctx, si, 0.f, Vec2f(0.5f));
        const auto [bs_t, w_t] = bsdf->sample(ctx, si, 0.99999f, Vec2f(0.5f));
        if (fr.F >= 1.f) { // total internal reflection
            EXPECT_EQ(bs_t.sampled_type, uint32_t(BSDFDeltaReflection));
            continue;
        }
        // Reflection and transmission probabilities are F and 1 - F: they sum to one (energy is split, not lost).
        EXPECT_NEAR(bs_r.pdf + bs_t.pdf, 1.f, 1e-6f);
        EXPECT_NEAR(bs_r.pdf, fr.F, 1e-6f);
        // Mirror direction and Snell's law n_i sin_i = n_t sin_t (relative: sin_t = sin_i / eta_it).
        EXPECT_NEAR(bs_r.wo.z, wi.z, 1e-6f);
        const float sin_i = std::sqrt(1.f - ci * ci), sin_t = std::sqrt(std::max(0.f, 1.f - bs_t.wo.z * bs_t.wo.z));
        EXPECT_NEAR(sin_t * bs_t.eta, sin_i, 1e-5f);
        EXPECT_LT(bs_t.wo.z * ci, 0.f);
        EXPECT_NEAR(norm(bs_t.wo), 1.f, 1e-5f);
        // Fresnel is the same from both sides of the interface (Stokes relations).
        EXPECT_NEAR(fresnel_dielectric(fr.cos_theta_t, eta).F, fr.F, 1e-5f);
        // Radiance mode scales transmission by eta_ti^2 = 1 / eta_it^2.
        const auto [bs_rad, w_rad] = bsdf->sample(BSDFContext(), si, 0.99999f, Vec2f(0.5f));
        EXPECT_NEAR(w_rad.x, 1.f / (bs_rad.eta * bs_rad.eta), 1e-5f);
    }
    // Normal incidence: F = ((eta - 1) / (eta + 1))^2.
    EXPECT_NEAR(fresnel_dielectric(1.f, eta).F, 0.04f, 1e-6f);
    // Index-matched interfaces do not reflect.
    EXPECT_EQ(fresnel_dielectric(0.3f, 1.f).F, 0.f);
}

TEST(BSDF, ConductorFresnelMatchesNormalIncidenceFormula) {
    const float eta = 0.2f, k = 3.f;
    const float expected = ((eta - 1) * (eta - 1) + k * k) / ((eta + 1) * (eta + 1) + k * k);
    EXPECT_NEAR(fresnel_conductor(1.f, eta, k), expected, 1e-6f);
    // With k = 0 the conductor formula reduces to the dielectric one.
    for (float c : {0.9f, 0.5f, 0.1f}) EXPECT_NEAR(fresnel_conductor(c, 1.5f, 0.f), fresnel_dielectric(c, 1.5f).F, 1e-5f);
    // Grazing incidence reflects everything.
    EXPECT_NEAR(fresnel_conductor(0.f, eta, k), 1.f, 1e-6f);
}

TEST(BSDF, ThinDielectricNullAndMask) {
    const auto thin = make_thindielectric(1.5f, tex(1.f), tex(1.f));
    const auto si = make_si(Vec3f(0.3f, 0.2f, -0.8f));
    const auto [r, wr] = thin->sample(BSDFContext(), si, 0.f, Vec2f(0.5f));
    const auto [t, wt] = thin->sample(BSDFContext(), si, 0.99999f, Vec2f(0.5f));
    EXPECT_NEAR(r.pdf + t.pdf, 1.f, 1e-6f);
    EXPECT_EQ(t.wo, -si.wi);
    const float F = fresnel_dielectric(-si.wi.z, 1.5f).F;
    EXPECT_NEAR(r.pdf, F + (1 - F) * (1 - F) * F / (1 - F * F), 1e-6f); // slab interreflection sum 2F / (1 + F)

    const auto null = make_null_bsdf();
    const auto [n, wn] = null->sample(BSDFContext(), si, 0.3f, Vec2f(0.5f));
    EXPECT_EQ(n.wo, -si.wi);
    EXPECT_EQ(wn, Color3f(1.f));
    EXPECT_EQ(n.sampled_type, uint32_t(BSDFNull));

    const auto mask = make_mask(tex(0.25f), make_diffuse(tex(0.5f)));
    const auto si_up = make_si(Vec3f(0.f, 0.f, 1.f));
    const auto [m, wm] = mask->sample(BSDFContext(), si_up, 0.5f, Vec2f(0.5f));
    EXPECT_EQ(m.sampled_type, uint32_t(BSDFNull));
    EXPECT_NEAR(m.pdf, 0.75f, 1e-6f);
    EXPECT_NEAR(mask->eval(BSDFContext(), si_up, Vec3f(0.f, 0.f, 1.f)).x, 0.25f * 0.5f * InvPi, 1e-6f);
}

TEST(BSDF, TwoSidedMirrorsBackSide) {
    const auto front = make_diffuse(tex(0.5f));
    const auto ts = make_twosided(front, nullptr);
    const Vec3f wi(0.3f, 0.2f, -0.9f), wo(-0.1f, 0.4f, -0.7f);
    const Color3f back = ts->eval(BSDFContext(), make_si(wi), normalize(wo));
    const Color3f mirrored = front->eval(BSDFContext(), make_si(Vec3f(wi.x, wi.y, -wi.z)), normalize(Vec3f(wo.x, wo.y, -wo.z)));
    EXPECT_EQ(back, mirrored);
    EXPECT_GT(back.x, 0.f);
    // One-sided BSDFs are black from below.
    EXPECT_EQ(front->eval(BSDFContext(), make_si(wi), normalize(wo)), Color3f(0.f));
}

TEST(BSDF, FresnelDiffuseReflectanceMatchesKnownValues) {
    // Hemispherical average of the Fresnel reflectance: 2 int F mu dmu. For eta = 1.5 the literature value
    // (e.g. d'Eon & Irving 2011 fit) is 0.0918; internal (1/1.5) is 1 - (1 - 0.0918) / 1.5^2 = 0.5963.
    EXPECT_NEAR(fresnel_diffuse_reflectance(1.5f), 0.0918f, 1e-3f);
    EXPECT_NEAR(fresnel_diffuse_reflectance(1.f / 1.5f), 1.f - (1.f - fresnel_diffuse_reflectance(1.5f)) / 2.25f, 1e-3f);
}

TEST(BSDF, FactoryParsesMitsubaParameters) {
    const SourceLocation loc{"scene.xml", 7};
    const LoadContext lctx;
    {
        Properties props("dielectric", loc);
        props.set("int_ior", std::string("water"), loc);
        props.set("ext_ior", 1.0, loc);
        const auto bsdf = std::static_pointer_cast<BSDF>(make_bsdf(props, lctx));
        EXPECT_TRUE(props.unqueried().empty());
        // Normal incidence reflectance of water/vacuum: ((1.333 - 1) / (1.333 + 1))^2.
        const auto [bs, w] = bsdf->sample(BSDFContext(), make_si(Vec3f(0.f, 0.f, 1.f)), 0.f, Vec2f(0.5f));
        EXPECT_NEAR(bs.pdf, sqr((1.333f - 1.f) / (1.333f + 1.f)), 1e-5f);
    }
    {
        Properties props("roughconductor", loc);
        props.set("material", std::string("Au"), loc);
        props.set("distribution", std::string("ggx"), loc);
        props.set("alpha_u", 0.2, loc);
        props.set("alpha_v", 0.4, loc);
        const auto bsdf = std::static_pointer_cast<BSDF>(make_bsdf(props, lctx));
        EXPECT_TRUE(props.unqueried().empty());
        const Color3f f = bsdf->eval(BSDFContext(), make_si(Vec3f(0.f, 0.f, 1.f)), Vec3f(0.f, 0.f, 1.f));
        EXPECT_GT(f.x, f.z); // gold reflects red more than blue
    }
    {
        Properties props("dielectric", loc);
        props.set("int_ior", std::string("unobtainium"), loc);
        EXPECT_THROW(make_bsdf(props, lctx), LoadError);
    }
    {
        Properties props("roughconductor", loc);
        props.set("material", std::string("Au"), loc);
        props.set("eta", 1.0, loc);
        EXPECT_THROW(make_bsdf(props, lctx), LoadError); // material and eta together
    }
    {
        Properties props("velvet", loc);
        try {
            make_bsdf(props, lctx);
            FAIL() << "expected an unsupported-plugin error";
        } catch (const LoadError& e) {
            EXPECT_NE(std::string(e.what()).find("scene.xml:7"), std::string::npos) << e.what();
        }
    }
}
