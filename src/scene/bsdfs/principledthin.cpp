// The thin principled BSDF as Mitsuba 3 implements it (Burley 2015): a two-sided sheet without refraction.
// Directions are mirrored to the side of wi (the model is symmetric); with wo' = wo mirrored to the upper
// hemisphere, h = normalize(wi + wo'), d = diff_trans / 2 and the GGX alphas from roughness/anisotropic:
//   specular reflection:   spec_trans F_t D G / (4 cos_i),  F_t = lerp(F, Schlick(tint R0(eta)), spec_tint)
//   specular transmission: spec_trans base_color (1 − F) D' G' / (4 cos_i), D' with roughness scaled by
//                          (0.65 eta − 0.35) (Burley 2015 Fig. 15), wo = wo' mirrored through the sheet
//   diffuse reflection:    (1 − spec_trans)(1 − d) (base_color/π diffuse_shape + sheen) |cos_o|
//   diffuse transmission:  (1 − spec_trans) d base_color/π |cos_o|
// F is the dielectric Fresnel of eta. Lobes are chosen with probabilities spec_trans/2, spec_trans/2,
// (1 − spec_trans)(1 − d), (1 − spec_trans) d, each times its sampling rate, normalized.
//
// Mitsuba 3 parameters (src/bsdfs/principledthin.cpp):
//   base_color                            spectrum|texture  0.5  base color
//   roughness                             float|texture     0.5  specular roughness (α = roughness²)
//   anisotropic                           float|texture     0.0  degree of anisotropy
//   spec_trans                            float|texture     0.0  diffuse (0) to specular (1) response
//   eta                                   float|texture     1.5  relative IOR of the sheet
//   spec_tint                             float|texture     0.0  base_color tint of the reflection
//   sheen, sheen_tint                     float|texture     0.0  sheen lobe and its base_color tint
//   flatness                              float|texture     0.0  diffuse (0) to fake subsurface (1)
//   diff_trans                            float|texture     0.0  diffuse energy sent through (0 .. 2)
//   specular_reflectance_sampling_rate    float             1.0  relative sampling rates of the lobes
//   specular_transmittance_sampling_rate  float             1.0
//   diffuse_reflectance_sampling_rate     float             1.0
//   diffuse_transmittance_sampling_rate   float             1.0
#include "core/fresnel.h"
#include "core/warp.h"
#include "scene/bsdfs/bsdfs.h"
#include "scene/bsdfs/principled_lobes.h"

namespace penumbra {

using namespace principled;

class PrincipledThinBSDF final : public BSDFBase<PrincipledThinBSDF> {
  public:
    explicit PrincipledThinBSDF(const PrincipledThinParams& p) : p_(p) {
        flags_ = BSDFDiffuseReflection | BSDFDiffuseTransmission | BSDFGlossyReflection |
                 (p_.has_spec_trans ? BSDFGlossyTransmission : 0u);
    }

    template <typename T>
    Color3<T> eval_t(const BSDFContext&, const SurfaceInteraction<T>& si, const Vec3<T>& wo_in) const {
        using std::abs;
        if (si.wi.z == T(0)) return Color3<T>(T(0));
        const bool flip = si.wi.z < T(0);
        const Vec3<T> wi = flip ? -si.wi : si.wi, wo = flip ? -wo_in : wo_in;
        const T ci = wi.z, co = wo.z;
        const bool reflect = co > T(0), refract = co < T(0);
        if (!reflect && !refract) return Color3<T>(T(0));
        const Color3<T> base = p_.base_color->eval(si);
        const T roughness = p_.roughness->eval_1(si), spec_trans = p_.spec_trans->eval_1(si);
        const T diff_trans = T(0.5f) * p_.diff_trans->eval_1(si);
        const Vec3<T> h = normalize(wi + Vec3<T>(wo.x, wo.y, abs(wo.z)));
        Color3<T> value(T(0));
        if (spec_trans > T(0) && microfacet_compatible(h, wi, wo, reflect)) {
            const T eta = p_.eta->eval_1(si), anisotropic = p_.anisotropic->eval_1(si);
            const T F = fresnel_dielectric(dot(wi, h), eta).F;
            if (reflect) {
                const MicrofacetDistribution<T> distr = specular_distribution(roughness, anisotropic);
                const T spec_tint = p_.spec_tint->eval_1(si);
                const Color3<T> Ft =
                    Color3<T>((T(1) - spec_tint) * F) +
                    schlick_fresnel(tint_color(base) * schlick_r0(eta), dot(wi, h), eta) * spec_tint;
                value += Ft * (spec_trans * distr.D(h) * distr.G(wi, wo, h) / (T(4) * ci));
            } else {
                const MicrofacetDistribution<T> distr =
                    transmission_distribution(roughness, anisotropic, eta);
                value += base * (spec_trans * (T(1) - F) * distr.D(h) * distr.G(wi, wo, h) / (T(4) * ci));
            }
        }
        if (!(spec_trans < T(1))) return value;
        if (reflect && diff_trans < T(1)) {
            const T cos_d = dot(h, wo), w = (T(1) - spec_trans) * (T(1) - diff_trans) * co;
            value += base * (w * T(InvPi) * diffuse_shape(ci, co, cos_d, roughness, p_.flatness->eval_1(si)));
            const T sheen = p_.sheen->eval_1(si);
            if (sheen > T(0)) value += sheen_value(sheen, p_.sheen_tint->eval_1(si), base, cos_d) * w;
        }
        if (refract && diff_trans > T(0)) value += base * ((T(1) - spec_trans) * diff_trans * T(InvPi) * -co);
        return value;
    }

    template <typename T>
    T pdf_t(const BSDFContext&, const SurfaceInteraction<T>& si, const Vec3<T>& wo_in) const {
        using std::abs;
        if (si.wi.z == T(0)) return T(0);
        const bool flip = si.wi.z < T(0);
        const Vec3<T> wi = flip ? -si.wi : si.wi, wo = flip ? -wo_in : wo_in;
        const bool reflect = wo.z > T(0), refract = wo.z < T(0);
        if (!reflect && !refract) return T(0);
        const Lobes<T> p = lobe_probabilities(si);
        T pdf(0);
        const Vec3<T> wo_r(wo.x, wo.y, abs(wo.z));
        const Vec3<T> h = normalize(wi + wo_r);
        const T spec = reflect ? p.spec_reflect : p.spec_trans;
        if (spec > T(0) && microfacet_compatible(h, wi, wo, reflect)) {
            const T roughness = p_.roughness->eval_1(si), anisotropic = p_.anisotropic->eval_1(si);
            const MicrofacetDistribution<T> distr =
                reflect ? specular_distribution(roughness, anisotropic)
                        : transmission_distribution(roughness, anisotropic, p_.eta->eval_1(si));
            pdf += spec * distr.pdf(wi, h) / abs(T(4) * dot(wo_r, h));
        }
        pdf += (reflect ? p.diffuse_reflect : p.diffuse_trans) * T(InvPi) * abs(wo.z);
        return pdf;
    }

    // Mitsuba's order on [0, 1): specular reflection, specular transmission, diffuse reflection, diffuse
    // transmission; sampled on wi's side and mirrored back.
    std::pair<BSDFSample, Color3f> sample(const BSDFContext& ctx, const SurfaceInteraction3f& si, float u1,
                                          const Vec2f& u2) const override {
        BSDFSample bs;
        if (si.wi.z == 0.f) return {bs, Color3f(0.f)};
        const bool flip = si.wi.z < 0.f;
        const Vec3f wi = flip ? -si.wi : si.wi;
        const Lobes<float> p = lobe_probabilities(si);
        Vec3f wo;
        if (u1 < p.spec_reflect + p.spec_trans) {
            const bool reflection = u1 < p.spec_reflect;
            const float roughness = p_.roughness->eval_1(si), anisotropic = p_.anisotropic->eval_1(si);
            const MicrofacetDistribution<float> distr =
                reflection ? specular_distribution(roughness, anisotropic)
                           : transmission_distribution(roughness, anisotropic, p_.eta->eval_1(si));
            const Vec3f m = distr.sample(wi, u2);
            wo = reflect(wi, m);
            if (!(wo.z > 0.f)) return {bs, Color3f(0.f)};
            if (!reflection) wo.z = -wo.z; // no bending through a thin sheet
            if (!microfacet_compatible(m, wi, wo, reflection)) return {bs, Color3f(0.f)};
            bs.sampled_type = reflection ? BSDFGlossyReflection : BSDFGlossyTransmission;
        } else if (u1 < p.spec_reflect + p.spec_trans + p.diffuse_reflect) {
            wo = warp::square_to_cosine_hemisphere(u2);
            bs.sampled_type = BSDFDiffuseReflection;
        } else {
            wo = -warp::square_to_cosine_hemisphere(u2);
            bs.sampled_type = BSDFDiffuseTransmission;
        }
        bs.wo = flip ? -wo : wo;
        bs.pdf = pdf_t<float>(ctx, si, bs.wo);
        if (!(bs.pdf > 0.f)) return {bs, Color3f(0.f)};
        return {bs, eval_t<float>(ctx, si, bs.wo) / bs.pdf};
    }

    Color3f eval_diffuse_reflectance(const SurfaceInteraction3f& si) const override {
        return p_.base_color->eval(si);
    }

    void traverse(ParamVisitor& v) override {
        v.put_object("eta", p_.eta.get());
        v.put_object("roughness", p_.roughness.get());
        v.put_object("diff_trans", p_.diff_trans.get());
        traverse_shared(v, p_);
    }

  private:
    template <typename T> struct Lobes { T spec_reflect, spec_trans, diffuse_reflect, diffuse_trans; };
    template <typename T> Lobes<T> lobe_probabilities(const SurfaceInteraction<T>& si) const {
        const T spec_trans = p_.spec_trans->eval_1(si), diff_trans = T(0.5f) * p_.diff_trans->eval_1(si);
        Lobes<T> p;
        p.spec_reflect = spec_trans * T(0.5f * p_.spec_reflect_rate);
        p.spec_trans = spec_trans * T(0.5f * p_.spec_trans_rate);
        p.diffuse_reflect = T(p_.diffuse_reflect_rate) * (T(1) - spec_trans) * (T(1) - diff_trans);
        p.diffuse_trans = T(p_.diffuse_trans_rate) * (T(1) - spec_trans) * diff_trans;
        const T total = p.spec_reflect + p.spec_trans + p.diffuse_reflect + p.diffuse_trans;
        if (!(total > T(0))) return {T(0), T(0), T(0), T(0)}; // all sampling rates 0: nothing is sampled
        return {p.spec_reflect / total, p.spec_trans / total, p.diffuse_reflect / total,
                p.diffuse_trans / total};
    }
    // The transmission lobe's roughness is scaled by (0.65 eta − 0.35) (Burley 2015, Fig. 15).
    template <typename T>
    static MicrofacetDistribution<T> transmission_distribution(const T& roughness, const T& anisotropic,
                                                               const T& eta) {
        return specular_distribution((T(0.65f) * eta - T(0.35f)) * roughness, anisotropic);
    }
    PrincipledThinParams p_;
};

BSDFPtr make_principledthin(const PrincipledThinParams& params) {
    return std::make_shared<PrincipledThinBSDF>(params);
}

BSDFPtr load_principledthin(const Properties& props) {
    PrincipledThinParams p;
    load_shared(props, p);
    p.eta = props.get_texture("eta", Color3f(1.5f));
    p.diff_trans = props.get_texture("diff_trans", Color3f(0.f));
    p.spec_reflect_rate = sampling_rate(props, "specular_reflectance_sampling_rate");
    p.spec_trans_rate = sampling_rate(props, "specular_transmittance_sampling_rate");
    p.diffuse_reflect_rate = sampling_rate(props, "diffuse_reflectance_sampling_rate");
    p.diffuse_trans_rate = sampling_rate(props, "diffuse_transmittance_sampling_rate");
    return make_principledthin(p);
}

} // namespace penumbra
