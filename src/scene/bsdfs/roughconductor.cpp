// Rough conductor (Walter et al. 2007): f = F(wi.h) D(h) G(wi, wo, h) / (4 cos_i cos_o), h = normalize(wi + wo).
//
// Mitsuba 3 parameters (src/bsdfs/roughconductor.cpp):
//   material               string             "none"       named conductor; "none" = eta 0, k 1 (perfect mirror)
//   eta, k                 spectrum|texture   0, 1         complex IOR (instead of material)
//   specular_reflectance   spectrum|texture   1.0          multiplier of the reflected light
//   distribution           string             "beckmann"   "beckmann" or "ggx"
//   alpha | alpha_u, alpha_v  float|texture   0.1          isotropic or anisotropic roughness
//   sample_visible         boolean            true         sample visible normals
#include "core/fresnel.h"
#include "scene/bsdfs/bsdfs.h"

namespace penumbra {

class RoughConductorBSDF final : public BSDFBase<RoughConductorBSDF> {
public:
    RoughConductorBSDF(const RoughnessParams& rough, TexturePtr eta, TexturePtr k, TexturePtr specular)
        : rough_(rough), eta_(std::move(eta)), k_(std::move(k)), specular_(std::move(specular)) {
        flags_ = BSDFGlossyReflection;
    }

    template <typename T> Color3<T> eval_t(const BSDFContext&, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        const T ci = si.wi.z, co = wo.z;
        if (!(ci > T(0) && co > T(0))) return Color3<T>(T(0));
        const MicrofacetDistribution<T> distr = distribution(si);
        const Vec3<T> h = normalize(si.wi + wo);
        const T D = distr.D(h);
        if (!(D > T(0))) return Color3<T>(T(0));
        const T value = D * distr.G(si.wi, wo, h) / (T(4) * ci);
        return specular_->eval(si) * fresnel_conductor(dot(si.wi, h), eta_->eval(si), k_->eval(si)) * value;
    }

    // Density of reflect(wi, m) for m ~ distr: pdf_m(m) / (4 wo.m).
    template <typename T> T pdf_t(const BSDFContext&, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        const T ci = si.wi.z, co = wo.z;
        if (!(ci > T(0) && co > T(0))) return T(0);
        const Vec3<T> h = normalize(si.wi + wo);
        if (!(dot(si.wi, h) > T(0) && dot(wo, h) > T(0))) return T(0);
        return distribution(si).pdf(si.wi, h) / (T(4) * dot(wo, h));
    }

    std::pair<BSDFSample, Color3f> sample(const BSDFContext& ctx, const SurfaceInteraction3f& si, float,
                                          const Vec2f& u) const override {
        BSDFSample bs;
        if (!(si.wi.z > 0.f)) return {bs, Color3f(0.f)};
        const Vec3f m = distribution(si).sample(si.wi, u);
        bs.wo = reflect(si.wi, m);
        bs.sampled_type = BSDFGlossyReflection;
        bs.pdf = pdf_t<float>(ctx, si, bs.wo);
        if (!(bs.pdf > 0.f)) return {bs, Color3f(0.f)};
        return {bs, eval_t<float>(ctx, si, bs.wo) / bs.pdf};
    }

    // Differential lobe of the isotropic roughness α (paper 002 §4.1): the positivized ∂D/∂α cos θ_m of
    // DifferentialNDF, reflected about the sampled normal. Anisotropic roughness has no lobe.
    bool has_differential_lobe(const SurfaceInteraction3f& si) const override {
        return rough_.alpha_u == rough_.alpha_v && !rough_.alpha_u->eval_1(constant_interaction(si)).is_constant();
    }
    BSDFSample sample_differential(const BSDFContext& ctx, const SurfaceInteraction3f& si, int sign, float,
                                   const Vec2f& u) const override {
        BSDFSample bs;
        if (!(si.wi.z > 0.f)) return bs;
        bs.wo = reflect(si.wi, differential_distribution(si).sample(sign, u));
        bs.sampled_type = BSDFGlossyReflection;
        bs.pdf = pdf_differential(ctx, si, sign, bs.wo);
        return bs;
    }
    // Density of reflect(wi, m) for m ~ the signed lobe: p_m(m) / (4 wo.m).
    float pdf_differential(const BSDFContext&, const SurfaceInteraction3f& si, int sign, const Vec3f& wo) const override {
        if (!(si.wi.z > 0.f && wo.z > 0.f)) return 0.f;
        const Vec3f h = normalize(si.wi + wo);
        const float d = dot(wo, h);
        if (!(d > 0.f)) return 0.f;
        return differential_distribution(si).pdf(sign, h) / (4.f * d);
    }

    void traverse(ParamVisitor& v) override {
        traverse_roughness(v, rough_);
        v.put_object("eta", eta_.get());
        v.put_object("k", k_.get());
        v.put_object("specular_reflectance", specular_.get());
    }

private:
    template <typename T> MicrofacetDistribution<T> distribution(const SurfaceInteraction<T>& si) const {
        MicrofacetDistribution<T> d;
        d.type = rough_.type;
        d.alpha_u = rough_.alpha_u->eval_1(si);
        d.alpha_v = rough_.alpha_v->eval_1(si);
        d.sample_visible = rough_.sample_visible;
        return d;
    }
    DifferentialNDF differential_distribution(const SurfaceInteraction3f& si) const {
        return {rough_.type, rough_.alpha_u->eval_1(si)};
    }
    RoughnessParams rough_;
    TexturePtr eta_, k_, specular_;
};

BSDFPtr make_roughconductor(const RoughnessParams& rough, TexturePtr eta, TexturePtr k, TexturePtr specular_reflectance) {
    return std::make_shared<RoughConductorBSDF>(rough, std::move(eta), std::move(k), std::move(specular_reflectance));
}

BSDFPtr load_roughconductor(const Properties& props) {
    TexturePtr eta, k;
    parse_conductor_ior(props, eta, k);
    const RoughnessParams rough = parse_roughness(props);
    return make_roughconductor(rough, eta, k, props.get_texture("specular_reflectance", Color3f(1.f)));
}

} // namespace penumbra
