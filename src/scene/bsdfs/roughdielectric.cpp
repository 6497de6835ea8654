// Rough dielectric interface (Walter et al. 2007). With eta the relative IOR seen from wi's side and
// h the microfacet normal (flipped to the upper hemisphere):
//   reflection:   f = F D G / (4 |cos_i| |cos_o|),                h = normalize(wi + wo)
//   transmission: f = |wi.h| |wo.h| eta^2 (1 - F) D G / (|cos_i| |cos_o| (wi.h + eta wo.h)^2) * s,
//                 h = normalize(wi + eta wo), s = 1/eta^2 in radiance mode (1 in importance mode).
// Normals are sampled from the (visible) distribution seen from wi's side; reflection is chosen with
// probability F(wi.h).
//
// Mitsuba 3 parameters (src/bsdfs/roughdielectric.cpp):
//   int_ior                  float|string       "bk7" (1.5046)     interior index of refraction
//   ext_ior                  float|string       "air" (1.000277)   exterior index of refraction
//   specular_reflectance     spectrum|texture   1.0                multiplier of the reflected light
//   specular_transmittance   spectrum|texture   1.0                multiplier of the transmitted light
//   distribution             string             "beckmann"         "beckmann" or "ggx"
//   alpha | alpha_u, alpha_v float|texture      0.1                isotropic or anisotropic roughness
//   sample_visible           boolean            true               sample visible normals
#include "core/fresnel.h"
#include "core/param.h"
#include "scene/bsdfs/bsdfs.h"

namespace penumbra {

class RoughDielectricBSDF final : public BSDFBase<RoughDielectricBSDF> {
public:
    RoughDielectricBSDF(const RoughnessParams& rough, float eta, TexturePtr reflectance, TexturePtr transmittance)
        : rough_(rough), eta_(eta), reflectance_(std::move(reflectance)), transmittance_(std::move(transmittance)) {
        flags_ = BSDFGlossyReflection | BSDFGlossyTransmission;
    }

    template <typename T> Color3<T> eval_t(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        using std::abs;
        const T ci = si.wi.z, co = wo.z;
        if (ci == T(0) || co == T(0)) return Color3<T>(T(0));
        const bool reflect = ci * co > T(0);
        const T eta_int = param_value<T>(eta_, eta_index_);
        const T eta = ci > T(0) ? eta_int : T(1.f) / eta_int;
        Vec3<T> h;
        if (!half_vector(si.wi, wo, reflect, eta, h)) return Color3<T>(T(0));
        const MicrofacetDistribution<T> distr = distribution(si);
        const T D = distr.D(h);
        if (!(D > T(0))) return Color3<T>(T(0));
        const T G = distr.G(si.wi, wo, h);
        const T F = fresnel_dielectric(dot(si.wi, h), eta_int).F;
        if (reflect) return reflectance_->eval(si) * (F * D * G / (T(4) * abs(ci)));
        const T wih = dot(si.wi, h), woh = dot(wo, h);
        // Radiance mode scales by 1/eta² (non-symmetric refraction), cancelling the eta² of the Jacobian.
        const T scale_eta2 = ctx.mode == TransportMode::Radiance ? T(1.f) : eta * eta;
        const T value = abs(scale_eta2 * (T(1) - F) * D * G * wih * woh / (ci * sqr(wih + eta * woh)));
        return transmittance_->eval(si) * value;
    }

    // pdf = pdf_m(h) * (F or 1 - F) * |dh/dwo|, dh/dwo = 1 / (4 wo.h) (reflection) or eta^2 wo.h / (wi.h + eta wo.h)^2.
    template <typename T> T pdf_t(const BSDFContext&, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        using std::abs;
        const T ci = si.wi.z, co = wo.z;
        if (ci == T(0) || co == T(0)) return T(0);
        const bool reflect = ci * co > T(0);
        const T eta_int = param_value<T>(eta_, eta_index_);
        const T eta = ci > T(0) ? eta_int : T(1.f) / eta_int;
        Vec3<T> h;
        if (!half_vector(si.wi, wo, reflect, eta, h)) return T(0);
        const T wih = dot(si.wi, h), woh = dot(wo, h);
        const T dh_dwo = reflect ? T(1) / (T(4) * woh) : eta * eta * woh / sqr(wih + eta * woh);
        const T F = fresnel_dielectric(wih, eta_int).F;
        const Vec3<T> wi_up = ci > T(0) ? si.wi : -si.wi;
        const T pm = sampling_distribution(si, ci).pdf(wi_up, h);
        return abs(pm * (reflect ? F : T(1) - F) * dh_dwo);
    }

    std::pair<BSDFSample, Color3f> sample(const BSDFContext& ctx, const SurfaceInteraction3f& si, float u1,
                                          const Vec2f& u2) const override {
        BSDFSample bs;
        const float ci = si.wi.z;
        if (ci == 0.f) return {bs, Color3f(0.f)};
        const Vec3f wi_up = ci > 0.f ? si.wi : -si.wi;
        const Vec3f m = sampling_distribution(si, ci).sample(wi_up, u2);
        const auto fr = fresnel_dielectric(dot(si.wi, m), eta_);
        if (u1 <= fr.F) {
            bs.wo = reflect(si.wi, m);
            bs.sampled_type = BSDFGlossyReflection;
            if (!(bs.wo.z * ci > 0.f)) return {bs, Color3f(0.f)};
        } else {
            bs.wo = refract(si.wi, m, fr.cos_theta_t, fr.eta_ti);
            bs.eta = fr.eta_it;
            bs.sampled_type = BSDFGlossyTransmission;
            if (!(bs.wo.z * ci < 0.f)) return {bs, Color3f(0.f)};
        }
        bs.pdf = pdf_t<float>(ctx, si, bs.wo);
        if (!(bs.pdf > 0.f)) return {bs, Color3f(0.f)};
        return {bs, eval_t<float>(ctx, si, bs.wo) / bs.pdf};
    }

    void traverse(ParamVisitor& v) override {
        v.put("eta", &eta_, 1, &eta_index_);
        traverse_roughness(v, rough_);
        v.put_object("specular_reflectance", reflectance_.get());
        v.put_object("specular_transmittance", transmittance_.get());
    }

private:
    // Generalized half vector in the upper hemisphere; false if degenerate or if wi/wo see the back of it.
    template <typename T> static bool half_vector(const Vec3<T>& wi, const Vec3<T>& wo, bool reflect, const T& eta, Vec3<T>& h) {
        h = wi + wo * (reflect ? T(1.f) : eta);
        const T len2 = squared_norm(h);
        if (!(len2 > T(0))) return false;
        h = normalize(h);
        if (h.z < T(0)) h = -h;
        return dot(wi, h) * wi.z > T(0) && dot(wo, h) * wo.z > T(0);
    }
    // Mitsuba widens the sampling roughness by (1.2 - 0.2 sqrt|cos_i|) when not sampling visible normals
    // (Walter et al. 2007, Sec. 5.3); eval always uses the true roughness.
    template <typename T> MicrofacetDistribution<T> distribution(const SurfaceInteraction<T>& si) const {
        MicrofacetDistribution<T> d;
        d.type = rough_.type;
        d.alpha_u = rough_.alpha_u->eval_1(si);
        d.alpha_v = rough_.alpha_v->eval_1(si);
        d.sample_visible = rough_.sample_visible;
        return d;
    }
    template <typename T> MicrofacetDistribution<T> sampling_distribution(const SurfaceInteraction<T>& si, const T& ci) const {
        using std::abs;
        using std::sqrt;
        MicrofacetDistribution<T> d = distribution(si);
        if (!d.sample_visible) {
            const T widen = T(1.2f) - T(0.2f) * sqrt(abs(ci));
            d.alpha_u = d.alpha_u * widen;
            d.alpha_v = d.alpha_v * widen;
        }
        return d;
    }
    RoughnessParams rough_;
    float eta_;
    int eta_index_ = -1;
    TexturePtr reflectance_, transmittance_;
};

BSDFPtr make_roughdielectric(const RoughnessParams& rough, float eta, TexturePtr specular_reflectance,
                             TexturePtr specular_transmittance) {
    return std::make_shared<RoughDielectricBSDF>(rough, eta, std::move(specular_reflectance),
                                                 std::move(specular_transmittance));
}

BSDFPtr load_roughdielectric(const Properties& props) {
    const float eta = relative_ior(props, "bk7");
    const RoughnessParams rough = parse_roughness(props);
    return make_roughdielectric(rough, eta, props.get_texture("specular_reflectance", Color3f(1.f)),
                                props.get_texture("specular_transmittance", Color3f(1.f)));
}

} // namespace penumbra
