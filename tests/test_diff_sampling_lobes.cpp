// Differential BSDF lobes (paper 002 §4.1): chi-square tests of each signed component's sampling against its
// density (GGX and Beckmann roughness after Zeltner et al. 2021, blend weight), and the sign of each component
// against ∂D/∂α evaluated with Var (the one physics code path).
#include "bsdf_chi2.h"
#include "diff/paths/differential_vertex.h"
#include "scene/bsdfs/bsdfs.h"

#include <gtest/gtest.h>

using namespace penumbra;
using namespace penumbra::test;

namespace {

// One signed component of a BSDF's differential lobe seen through the BSDF interface, so that the chi-square
// harness of the ordinary BSDFs tests it unchanged.
class SignedLobe final : public BSDF {
public:
    SignedLobe(BSDFPtr bsdf, int sign) : bsdf_(std::move(bsdf)), sign_(sign) { flags_ = BSDFGlossyReflection; }
    std::pair<BSDFSample, Color3f> sample(const BSDFContext& ctx, const SurfaceInteraction3f& si, float u1,
                                          const Vec2f& u2) const override {
        const BSDFSample bs = bsdf_->sample_differential(ctx, si, sign_, u1, u2);
        return {bs, Color3f(bs.pdf > 0.f ? 1.f : 0.f)};
    }
    Color3f eval(const BSDFContext&, const SurfaceInteraction3f&, const Vec3f&) const override { return Color3f(0.f); }
    float pdf(const BSDFContext& ctx, const SurfaceInteraction3f& si, const Vec3f& wo) const override {
        return bsdf_->pdf_differential(ctx, si, sign_, wo);
    }
    Color3<Var> eval(const BSDFContext&, const SurfaceInteraction<Var>&, const Vec3<Var>&) const override {
        return Color3<Var>(Var(0.f));
    }
    Var pdf(const BSDFContext&, const SurfaceInteraction<Var>&, const Vec3<Var>&) const override { return Var(0.f); }

private:
    BSDFPtr bsdf_;
    int sign_;
};

RoughnessParams isotropic(MicrofacetType type, float alpha) {
    RoughnessParams r;
    r.type = type;
    r.alpha_u = r.alpha_v = tex(alpha);
    return r;
}

BSDFPtr conductor(MicrofacetType type, float alpha) { return make_roughconductor(isotropic(type, alpha), tex(0.f), tex(1.f), tex(1.f)); }

struct LobeCase {
    std::string name;
    BSDFPtr bsdf;
    Vec3f wi;
    // Midpoint-rule resolution of the expected counts: the α = 0.1 lobes sit inside one cos θ bin and need a
    // finer rule, or the integration error alone fails the test.
    int sub = 16;
};

std::vector<LobeCase> lobe_cases() {
    const Vec3f normal(0.05f, 0.f, 1.f), oblique(0.5f, 0.2f, 0.7f), grazing(0.9f, 0.f, 0.2f);
    return {
        {"ggx_0.1_normal", conductor(MicrofacetType::GGX, 0.1f), normal, 64},
        {"ggx_0.3_oblique", conductor(MicrofacetType::GGX, 0.3f), oblique},
        {"ggx_0.6_grazing", conductor(MicrofacetType::GGX, 0.6f), grazing},
        {"beckmann_0.1_normal", conductor(MicrofacetType::Beckmann, 0.1f), normal, 64},
        {"beckmann_0.3_oblique", conductor(MicrofacetType::Beckmann, 0.3f), oblique},
        {"beckmann_0.6_grazing", conductor(MicrofacetType::Beckmann, 0.6f), grazing},
        {"blend_weight_oblique", make_blendbsdf(tex(0.4f), make_diffuse(tex(0.5f)), conductor(MicrofacetType::GGX, 0.2f)), oblique},
        {"blend_weight_grazing", make_blendbsdf(tex(0.7f), make_diffuse(tex(0.5f)), conductor(MicrofacetType::GGX, 0.4f)), grazing},
    };
}

} // namespace

TEST(DifferentialLobes, ChiSquareEachSignedComponent) {
    const auto cases = lobe_cases();
    // Overall significance 0.01, Sidak-corrected over the 2 × cases tests.
    const double alpha = 1.0 - std::pow(1.0 - 0.01, 1.0 / double(2 * cases.size()));
    uint64_t seed = 11;
    for (const auto& c : cases)
        for (int sign : {1, -1}) {
            const SignedLobe lobe(c.bsdf, sign);
            const auto r = bsdf_chi2(lobe, make_si(c.wi), BSDFContext{}, 200000, seed++, 20, 40, c.sub);
            EXPECT_GT(r.p_value, alpha) << c.name << (sign > 0 ? " (+)" : " (−)") << ": " << r.report;
        }
}

// The chi-square test must be able to fail: the positive lobe's samples against the negative lobe's density.
TEST(DifferentialLobes, ChiSquareRejectsTheWrongSign) {
    class Swapped final : public BSDF {
    public:
        explicit Swapped(BSDFPtr b) : b_(std::move(b)) { flags_ = BSDFGlossyReflection; }
        std::pair<BSDFSample, Color3f> sample(const BSDFContext& ctx, const SurfaceInteraction3f& si, float u1,
                                              const Vec2f& u2) const override {
            const BSDFSample bs = b_->sample_differential(ctx, si, 1, u1, u2);
            return {bs, Color3f(bs.pdf > 0.f ? 1.f : 0.f)};
        }
        Color3f eval(const BSDFContext&, const SurfaceInteraction3f&, const Vec3f&) const override { return Color3f(0.f); }
        float pdf(const BSDFContext& ctx, const SurfaceInteraction3f& si, const Vec3f& wo) const override {
            return b_->pdf_differential(ctx, si, -1, wo);
        }
        Color3<Var> eval(const BSDFContext&, const SurfaceInteraction<Var>&, const Vec3<Var>&) const override {
            return Color3<Var>(Var(0.f));
        }
        Var pdf(const BSDFContext&, const SurfaceInteraction<Var>&, const Vec3<Var>&) const override { return Var(0.f); }
        BSDFPtr b_;
    };
    const Swapped wrong(conductor(MicrofacetType::Beckmann, 0.3f));
    EXPECT_LT(bsdf_chi2(wrong, make_si(Vec3f(0.5f, 0.2f, 0.7f)), BSDFContext{}, 200000, 5).p_value, 1e-6);
}

// Each signed component covers exactly the normals where ∂D/∂α (from D() with Var) has its sign.
TEST(DifferentialLobes, SignsMatchTheDerivativeOfTheNdf) {
    PCG32 rng(3);
    for (MicrofacetType type : {MicrofacetType::GGX, MicrofacetType::Beckmann})
        for (float alpha : {0.05f, 0.3f, 0.8f}) {
            const DifferentialNDF lobe{type, alpha};
            for (int sign : {1, -1})
                for (int i = 0; i < 2000; ++i) {
                    const Vec3f m = lobe.sample(sign, Vec2f(rng.next_float(), rng.next_float()));
                    Tape& tape = Tape::current();
                    tape.clear();
                    MicrofacetDistribution<Var> d;
                    d.type = type;
                    d.alpha_u = d.alpha_v = Var::parameter(alpha, 0);
                    const Var D = d.D(Vec3<Var>(m));
                    double dD = 0.0;
                    std::vector<float> scratch;
                    tape.backward({{D.id, 1.f}}, &dD, scratch);
                    // Away from the sign change (s = 1) float rounding cannot flip the sign.
                    const double s = (1.0 - double(m.z) * m.z) / (double(m.z) * m.z * alpha * alpha);
                    if (std::abs(s - 1.0) < 1e-3) continue;
                    EXPECT_GT(dD * sign, 0.0) << "alpha " << alpha << ", s " << s;
                    EXPECT_GT(lobe.pdf(sign, m), 0.f);
                    EXPECT_EQ(lobe.pdf(-sign, m), 0.f);
                }
        }
    Tape::current().clear();
}
