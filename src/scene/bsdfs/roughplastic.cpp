// Rough plastic: a rough dielectric coating (isotropic microfacets) over a diffuse base:
//   f cos_o = s F(wi.h) D G / (4 cos_i) + R' T(cos_i) T(cos_o) cos_o / (pi eta^2),
// where T(mu) is the rough coating's directional transmittance seen from outside (light refracted in, masked
// by G1 of the refracted direction; not 1 - reflectance), R' = R / (1 - Fdr_int) (or R / (1 - R Fdr_int) if
// nonlinear) and Fdr_int = 2 int E_int(mu) mu dmu is the internal albedo, E_int the reflectance from inside.
// Both are tabulated at load time as Mitsuba does (64 entries mu_i = max(1e-6, i / 63); Fdr_int = 2 mean_i
// E_int(mu_i) mu_i; Gauss-Legendre quadrature over visible normals, core/microfacet.h).
//
// Mitsuba 3 parameters (src/bsdfs/roughplastic.cpp):
//   distribution           string             "beckmann"               "beckmann" or "ggx"
//   alpha                  float              0.1                      roughness (isotropic only)
//   sample_visible         boolean            true                     sample visible normals
//   int_ior                float|string       "polypropylene" (1.49)   interior index of refraction
//   ext_ior                float|string       "air" (1.000277)         exterior index of refraction
//   diffuse_reflectance    spectrum|texture   0.5                      base reflectance
//   specular_reflectance   spectrum|texture   1.0                      multiplier of the specular lobe
//   nonlinear              boolean            false                    account for color shifts by interreflection
#include "core/fresnel.h"
#include "core/warp.h"
#include "scene/bsdfs/bsdfs.h"

#include <tbb/parallel_for.h>

#include <array>

namespace penumbra {

namespace {

constexpr int AlbedoRes = 64;

} // namespace

class RoughPlasticBSDF final : public BSDFBase<RoughPlasticBSDF> {
public:
    RoughPlasticBSDF(MicrofacetType type, float alpha, bool sample_visible, float eta, TexturePtr diffuse,
                     TexturePtr specular, bool nonlinear)
        : eta_(eta), inv_eta2_(1.f / (eta * eta)), diffuse_(std::move(diffuse)), specular_(std::move(specular)),
          nonlinear_(nonlinear) {
        distr_.type = type;
        distr_.alpha_u = distr_.alpha_v = alpha;
        distr_.sample_visible = sample_visible;
        const Color3f d = diffuse_->mean(), s = specular_->mean();
        const float dm = (d.x + d.y + d.z) / 3.f, sm = (s.x + s.y + s.z) / 3.f;
        specular_weight_ = sm / (dm + sm);
        // Table entries in parallel (each is a 32^2 or 128^2 quadrature), summed in order: deterministic.
        std::array<float, AlbedoRes> internal{};
        tbb::parallel_for(0, AlbedoRes, [&](int i) {
            const float mu = std::max(1e-6f, float(i) / (AlbedoRes - 1));
            const Vec3f wi(std::sqrt(1.f - mu * mu), 0.f, mu);
            external_transmittance_[i] =
                rough_interface_albedo(distr_, wi, eta_, InterfaceLobe::Transmission);
            internal[i] = rough_interface_albedo(distr_, wi, 1.f / eta_, InterfaceLobe::Reflection) * mu;
        });
        double sum = 0.0;
        for (const float v : internal)
            sum += v;
        internal_reflectance_ = float(2.0 * sum / AlbedoRes);
        flags_ = BSDFGlossyReflection | BSDFDiffuseReflection;
    }

    template <typename T> Color3<T> eval_t(const BSDFContext&, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        const T ci = si.wi.z, co = wo.z;
        if (!(ci > T(0) && co > T(0))) return Color3<T>(T(0));
        const MicrofacetDistribution<T> distr = distribution<T>();
        const Vec3<T> h = normalize(si.wi + wo);
        const T spec = fresnel_dielectric(dot(si.wi, h), eta_).F * distr.D(h) * distr.G(si.wi, wo, h) / (T(4) * ci);
        const Color3<T> R = diffuse_->eval(si);
        const Color3<T> Rp = nonlinear_ ? R / (Color3<T>(T(1)) - R * T(internal_reflectance_))
                                        : R / T(1.f - internal_reflectance_);
        const T diff = T(InvPi * inv_eta2_) * co * transmittance(ci) * transmittance(co);
        return specular_->eval(si) * spec + Rp * diff;
    }
    template <typename T> T pdf_t(const BSDFContext&, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        const T ci = si.wi.z, co = wo.z;
        if (!(ci > T(0) && co > T(0))) return T(0);
        const T ps = prob_specular(ci);
        const Vec3<T> h = normalize(si.wi + wo);
        const T spec = dot(wo, h) > T(0) ? distribution<T>().pdf(si.wi, h) / (T(4) * dot(wo, h)) : T(0);
        return ps * spec + (T(1) - ps) * warp::square_to_cosine_hemisphere_pdf(wo);
    }
    std::pair<BSDFSample, Color3f> sample(const BSDFContext& ctx, const SurfaceInteraction3f& si, float u1,
                                          const Vec2f& u2) const override {
        BSDFSample bs;
        if (!(si.wi.z > 0.f)) return {bs, Color3f(0.f)};
        if (u1 < prob_specular(si.wi.z)) {
            bs.wo = reflect(si.wi, distr_.sample(si.wi, u2));
            bs.sampled_type = BSDFGlossyReflection;
        } else {
            bs.wo = warp::square_to_cosine_hemisphere(u2);
            bs.sampled_type = BSDFDiffuseReflection;
        }
        bs.pdf = pdf_t<float>(ctx, si, bs.wo);
        if (!(bs.pdf > 0.f)) return {bs, Color3f(0.f)};
        return {bs, eval_t<float>(ctx, si, bs.wo) / bs.pdf};
    }
    Color3f eval_diffuse_reflectance(const SurfaceInteraction3f& si) const override { return diffuse_->eval(si); }

    void traverse(ParamVisitor& v) override {
        v.put_object("diffuse_reflectance", diffuse_.get());
        v.put_object("specular_reflectance", specular_.get());
    }

private:
    template <typename T> MicrofacetDistribution<T> distribution() const {
        MicrofacetDistribution<T> d;
        d.type = distr_.type;
        d.alpha_u = d.alpha_v = T(distr_.alpha_u);
        d.sample_visible = distr_.sample_visible;
        return d;
    }
    // Linear interpolation of the T(mu) table.
    template <typename T> T transmittance(const T& mu) const {
        const T x = mu * T(AlbedoRes - 1);
        const int i = std::min(int(detach(x)), AlbedoRes - 2);
        const T w = x - T(float(i));
        return (T(1) - w) * T(external_transmittance_[i]) + w * T(external_transmittance_[i + 1]);
    }
    // Specular probability (1 - t_i) w_s / ((1 - t_i) w_s + t_i (1 - w_s)).
    template <typename T> T prob_specular(const T& ci) const {
        const T ti = transmittance(ci);
        const T s = (T(1) - ti) * T(specular_weight_), d = ti * T(1.f - specular_weight_);
        return s / (s + d);
    }
    MicrofacetDistribution<float> distr_;
    float eta_, inv_eta2_;
    TexturePtr diffuse_, specular_;
    bool nonlinear_;
    float specular_weight_ = 0.5f, internal_reflectance_ = 0.f;
    std::array<float, AlbedoRes> external_transmittance_{};
};

BSDFPtr make_roughplastic(MicrofacetType type, float alpha, bool sample_visible, float eta, TexturePtr diffuse_reflectance,
                          TexturePtr specular_reflectance, bool nonlinear) {
    return std::make_shared<RoughPlasticBSDF>(type, alpha, sample_visible, eta, std::move(diffuse_reflectance),
                                              std::move(specular_reflectance), nonlinear);
}

BSDFPtr load_roughplastic(const Properties& props) {
    const MicrofacetType type = parse_distribution(props);
    if (props.has("alpha_u") || props.has("alpha_v"))
        props.raise(props.has("alpha_u") ? "alpha_u" : "alpha_v",
                    "roughplastic does not support anisotropic roughness (use \"alpha\")");
    const float alpha = props.get_float("alpha", 0.1f);
    const bool sample_visible = props.get_bool("sample_visible", true);
    const PlasticParams p = parse_plastic(props);
    return make_roughplastic(type, alpha, sample_visible, p.eta, p.diffuse_reflectance,
                             p.specular_reflectance, p.nonlinear);
}

} // namespace penumbra
