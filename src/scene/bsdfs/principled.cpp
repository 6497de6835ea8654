// The Disney principled BSDF as Mitsuba 3 implements it (Burley 2012, 2015). With brdf = (1 − metallic)
// (1 − spec_trans), bsdf = (1 − metallic) spec_trans, GGX alphas from roughness/anisotropic and h the
// (generalized) half vector:
//   specular reflection:   F_p D G / (4 |cos_i|); on the front side F_p = (1 − metallic)(1 − spec_tint) F
//                          + metallic Schlick(base_color) + (1 − metallic) spec_tint Schlick(tint R0(eta)),
//                          on the back side F_p = bsdf F
//   specular transmission: sqrt(base_color) bsdf |s (1 − F) D G η² (wi·h)(wo·h) / (cos_i (wi·h + η wo·h)²)|
//   clearcoat (front):     clearcoat/4 Schlick(0.04) GTR1(h) G_0.25 |cos_o|
//   diffuse (front):       brdf base_color/π diffuse_shape |cos_o| + (1 − metallic) sheen |cos_o|
// F is the dielectric Fresnel of eta; s = 1/η² in radiance mode. Lobes are chosen with Mitsuba's
// probabilities (diffuse brdf, clearcoat clearcoat/4, specular reflection 1 − bsdf (1 − F), transmission
// bsdf (1 − F), each times its sampling rate, normalized); the specular normal is drawn from the visible
// GGX normals.
//
// Mitsuba 3 parameters (src/bsdfs/principled.cpp):
//   base_color                         spectrum|texture  0.5  base color
//   roughness                          float|texture     0.5  specular roughness (α = roughness²)
//   anisotropic                        float|texture     0.0  degree of anisotropy
//   metallic                           float|texture     0.0  metallicness
//   spec_trans                         float|texture     0.0  blend of the BRDF (0) and BSDF (1) lobes
//   eta                                float             –    relative IOR (instead of `specular`)
//   specular                           float             0.5  eta = 2 / (1 − sqrt(0.08 specular)) − 1
//   spec_tint                          float|texture     0.0  base_color tint of the dielectric reflection
//   sheen, sheen_tint                  float|texture     0.0  sheen lobe and its base_color tint
//   flatness                           float|texture     0.0  diffuse (0) to fake subsurface (1)
//   clearcoat, clearcoat_gloss         float|texture     0.0  clearcoat lobe and its glossiness
//   main_specular_sampling_rate        float             1.0  relative sampling rate of the specular lobes
//   clearcoat_sampling_rate            float             1.0  ... of the clearcoat
//   diffuse_reflectance_sampling_rate  float             1.0  ... of the diffuse lobe
#include "core/fresnel.h"
#include "core/param.h"
#include "core/warp.h"
#include "scene/bsdfs/bsdfs.h"
#include "scene/bsdfs/principled_lobes.h"

namespace penumbra {

using namespace principled;

class PrincipledBSDF final : public BSDFBase<PrincipledBSDF> {
  public:
    explicit PrincipledBSDF(const PrincipledParams& p) : p_(p) {
        flags_ =
            BSDFDiffuseReflection | BSDFGlossyReflection | (p_.has_spec_trans ? BSDFGlossyTransmission : 0u);
    }

    template <typename T>
    Color3<T> eval_t(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        using std::abs;
        const T ci = si.wi.z, co = wo.z;
        const bool reflect = ci * co > T(0), refract = ci * co < T(0);
        if (!reflect && !refract) return Color3<T>(T(0));
        const Color3<T> base = p_.base_color->eval(si);
        const T roughness = p_.roughness->eval_1(si), metallic = p_.metallic->eval_1(si);
        const T spec_trans = p_.spec_trans->eval_1(si);
        const T brdf = (T(1) - metallic) * (T(1) - spec_trans), bsdf = (T(1) - metallic) * spec_trans;
        const bool front = ci > T(0);
        const T eta = eta_value<T>(), eta_path = front ? eta : T(1) / eta;
        const Vec3<T> h = half_vector(si.wi, wo, reflect, eta_path);
        const T wih = dot(si.wi, h), woh = dot(wo, h);
        const T F = fresnel_dielectric(wih, eta).F;
        const MicrofacetDistribution<T> distr = specular_distribution(roughness, p_.anisotropic->eval_1(si));
        const bool compatible = microfacet_compatible(h, si.wi, wo, reflect);
        Color3<T> value(T(0));
        if (reflect && compatible && F > T(0)) {
            Color3<T> Fp(bsdf * F);
            if (front) {
                const T spec_tint = p_.spec_tint->eval_1(si);
                const Color3<T> r0_tint = tint_color(base) * schlick_r0(wih >= T(0) ? eta : T(1) / eta);
                Fp = Color3<T>((T(1) - metallic) * (T(1) - spec_tint) * F) +
                     schlick_fresnel(base, wih, eta) * metallic +
                     schlick_fresnel(r0_tint, wih, eta) * ((T(1) - metallic) * spec_tint);
            }
            value += Fp * (distr.D(h) * distr.G(si.wi, wo, h) / (T(4) * abs(ci)));
        }
        if (refract && compatible && bsdf > T(0) && F < T(1)) {
            // Radiance mode scales by 1/η² (non-symmetric refraction).
            const T scale = ctx.mode == TransportMode::Radiance ? T(1) / sqr(eta_path) : T(1);
            const T t = abs(scale * (T(1) - F) * distr.D(h) * distr.G(si.wi, wo, h) * sqr(eta_path) * wih *
                            woh / (ci * sqr(wih + eta_path * woh)));
            value += sqrt_color(base) * (bsdf * t);
        }
        if (!(reflect && front)) return value;
        const T clearcoat = p_.clearcoat->eval_1(si);
        if (compatible && clearcoat > T(0)) {
            const GTR1<T> cc{clearcoat_alpha(p_.clearcoat_gloss->eval_1(si))};
            const T Fcc = schlick_fresnel(T(0.04f), wih, eta);
            value += Color3<T>(T(0.25f) * clearcoat * Fcc * cc.D(h) * clearcoat_G(si.wi, wo, h) * co);
        }
        if (brdf > T(0)) {
            const T flatness = p_.flatness->eval_1(si);
            value += base * (brdf * co * T(InvPi) * diffuse_shape(ci, co, woh, roughness, flatness));
            const T sheen = p_.sheen->eval_1(si);
            if (sheen > T(0) && T(1) - metallic > T(0))
                value += sheen_value(sheen, p_.sheen_tint->eval_1(si), base, woh) * ((T(1) - metallic) * co);
        }
        return value;
    }

    template <typename T>
    T pdf_t(const BSDFContext&, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        using std::abs;
        const T ci = si.wi.z, co = wo.z;
        const bool reflect = ci * co > T(0), refract = ci * co < T(0);
        if (!reflect && !refract) return T(0);
        const T metallic = p_.metallic->eval_1(si), spec_trans = p_.spec_trans->eval_1(si);
        const bool front = ci > T(0);
        const T bsdf = (T(1) - metallic) * spec_trans;
        if (!front && !(bsdf > T(0))) return T(0); // sample() never leaves from inside
        const T eta = eta_value<T>(), eta_path = front ? eta : T(1) / eta;
        const Vec3<T> h = half_vector(si.wi, wo, reflect, eta_path);
        const T wih = dot(si.wi, h), woh = dot(wo, h);
        const Lobes<T> p =
            lobe_probabilities(si, metallic, spec_trans, fresnel_dielectric(wih, eta).F, front);
        const T dh_dwo = abs(reflect ? T(1) / (T(4) * woh) : sqr(eta_path) * woh / sqr(wih + eta_path * woh));
        const bool compatible = microfacet_compatible(h, si.wi, wo, reflect);
        T pdf(0);
        if (compatible) {
            const MicrofacetDistribution<T> distr =
                specular_distribution(p_.roughness->eval_1(si), p_.anisotropic->eval_1(si));
            pdf += (reflect ? p.spec_reflect : p.spec_trans) * distr.pdf(front ? si.wi : -si.wi, h) * dh_dwo;
            if (reflect && p.clearcoat > T(0))
                pdf += p.clearcoat * GTR1<T>{clearcoat_alpha(p_.clearcoat_gloss->eval_1(si))}.pdf(h) * dh_dwo;
        }
        if (reflect && front) pdf += p.diffuse * warp::square_to_cosine_hemisphere_pdf(wo);
        return pdf;
    }

    // Mitsuba's order on [0, 1): diffuse, clearcoat, specular transmission, specular reflection.
    std::pair<BSDFSample, Color3f> sample(const BSDFContext& ctx, const SurfaceInteraction3f& si, float u1,
                                          const Vec2f& u2) const override {
        BSDFSample bs;
        const float ci = si.wi.z;
        const float metallic = p_.metallic->eval_1(si), spec_trans = p_.spec_trans->eval_1(si);
        const bool front = ci > 0.f;
        if (ci == 0.f || !(front || (1.f - metallic) * spec_trans > 0.f)) return {bs, Color3f(0.f)};
        const MicrofacetDistribution<float> distr =
            specular_distribution(p_.roughness->eval_1(si), p_.anisotropic->eval_1(si));
        const Vec3f m = distr.sample(front ? si.wi : -si.wi, u2);
        const FresnelDielectric<float> fr = fresnel_dielectric(dot(si.wi, m), eta_value<float>());
        const Lobes<float> p = lobe_probabilities(si, metallic, spec_trans, fr.F, front);
        bool reflection = true;
        if (u1 < p.diffuse) {
            bs.wo = warp::square_to_cosine_hemisphere(u2);
            bs.sampled_type = BSDFDiffuseReflection;
        } else if (u1 < p.diffuse + p.clearcoat) {
            const float alpha = clearcoat_alpha(p_.clearcoat_gloss->eval_1(si));
            const Vec3f mc = GTR1<float>::sample(alpha, u2);
            bs.wo = reflect(si.wi, mc);
            bs.sampled_type = BSDFGlossyReflection;
            if (!microfacet_compatible(mc, si.wi, bs.wo, true)) return {bs, Color3f(0.f)};
        } else if (u1 < p.diffuse + p.clearcoat + p.spec_trans) {
            bs.wo = refract(si.wi, m, fr.cos_theta_t, fr.eta_ti);
            bs.eta = fr.eta_it;
            bs.sampled_type = BSDFGlossyTransmission;
            reflection = false;
            if (!microfacet_compatible(m, si.wi, bs.wo, false)) return {bs, Color3f(0.f)};
        } else {
            bs.wo = reflect(si.wi, m);
            bs.sampled_type = BSDFGlossyReflection;
            if (!microfacet_compatible(m, si.wi, bs.wo, true)) return {bs, Color3f(0.f)};
        }
        if (reflection ? !(ci * bs.wo.z > 0.f) : !(ci * bs.wo.z < 0.f)) return {bs, Color3f(0.f)};
        bs.pdf = pdf_t<float>(ctx, si, bs.wo);
        if (!(bs.pdf > 0.f)) return {bs, Color3f(0.f)};
        return {bs, eval_t<float>(ctx, si, bs.wo) / bs.pdf};
    }

    Color3f eval_diffuse_reflectance(const SurfaceInteraction3f& si) const override {
        return p_.base_color->eval(si);
    }

    // Mitsuba's keys; the IOR is `eta` or `specular`, whichever the scene gave.
    void traverse(ParamVisitor& v) override {
        v.put_object("clearcoat", p_.clearcoat.get());
        v.put_object("clearcoat_gloss", p_.clearcoat_gloss.get());
        v.put_object("metallic", p_.metallic.get());
        if (p_.eta_given)
            v.put("eta", &p_.eta, 1, &ior_index_);
        else
            v.put("specular", &p_.specular, 1, &ior_index_);
        v.put_object("roughness", p_.roughness.get());
        traverse_shared(v, p_);
    }

  private:
    template <typename T> struct Lobes { T diffuse, clearcoat, spec_trans, spec_reflect; };
    // Mitsuba's lobe selection probabilities; on the back side only the specular interface is sampled.
    template <typename T>
    Lobes<T> lobe_probabilities(const SurfaceInteraction<T>& si, const T& metallic, const T& spec_trans,
                                const T& F, bool front) const {
        const T bsdf = (T(1) - metallic) * spec_trans;
        const T srate = T(p_.spec_rate);
        Lobes<T> p;
        p.spec_reflect = front ? srate * (T(1) - bsdf * (T(1) - F)) : F;
        p.spec_trans = front ? srate * bsdf * (T(1) - F) : T(1) - F;
        p.clearcoat = front ? T(0.25f * p_.clearcoat_rate) * p_.clearcoat->eval_1(si) : T(0);
        p.diffuse = front ? (T(1) - metallic) * (T(1) - spec_trans) * T(p_.diffuse_rate) : T(0);
        const T total = p.spec_reflect + p.spec_trans + p.clearcoat + p.diffuse;
        if (!(total > T(0))) return {T(0), T(0), T(0), T(0)}; // all sampling rates 0: nothing is sampled
        return {p.diffuse / total, p.clearcoat / total, p.spec_trans / total, p.spec_reflect / total};
    }
    // Relative IOR: `eta`, or from `specular` = 12.5 R0 (Burley 2012): eta = 2 / (1 − sqrt(0.08
    // specular)) − 1.
    template <typename T> T eta_value() const {
        using std::sqrt;
        if (p_.eta_given) return param_value<T>(p_.eta, ior_index_);
        return T(2) / (T(1) - sqrt(T(0.08f) * param_value<T>(p_.specular, ior_index_))) - T(1);
    }
    // Half vector wi + wo (reflection) or wi + η wo (transmission), flipped to the upper hemisphere.
    template <typename T>
    static Vec3<T> half_vector(const Vec3<T>& wi, const Vec3<T>& wo, bool reflect, const T& eta_path) {
        const Vec3<T> h = normalize(wi + wo * (reflect ? T(1) : eta_path));
        return h.z < T(0) ? -h : h;
    }
    PrincipledParams p_;
    int ior_index_ = -1;
};

BSDFPtr make_principled(const PrincipledParams& params) { return std::make_shared<PrincipledBSDF>(params); }

BSDFPtr load_principled(const Properties& props) {
    PrincipledParams p;
    load_shared(props, p);
    p.metallic = props.get_texture("metallic", Color3f(0.f));
    p.clearcoat = props.get_texture("clearcoat", Color3f(0.f));
    p.clearcoat_gloss = props.get_texture("clearcoat_gloss", Color3f(0.f));
    p.spec_rate = sampling_rate(props, "main_specular_sampling_rate");
    p.clearcoat_rate = sampling_rate(props, "clearcoat_sampling_rate");
    p.diffuse_rate = sampling_rate(props, "diffuse_reflectance_sampling_rate");
    if (props.has("eta") && props.has("specular"))
        props.raise("specular", "specify either \"eta\" or \"specular\", not both");
    p.eta_given = props.has("eta");
    if (p.eta_given) {
        p.eta = props.get_float("eta");
        if (!(p.eta > 0.f)) props.raise("eta", "the relative index of refraction must be positive");
        // Mitsuba: an index-matched interface cannot transmit.
        if (p.has_spec_trans && p.eta == 1.f) p.eta = 1.001f;
    } else {
        p.specular = props.get_float("specular", 0.5f);
        if (!(p.specular >= 0.f && p.specular < 12.5f))
            props.raise("specular",
                        "specular must be in [0, 12.5) (eta = 2 / (1 - sqrt(0.08 specular)) - 1)");
        if (p.has_spec_trans && p.specular == 0.f) p.specular = 1e-3f;
    }
    return make_principled(p);
}

} // namespace penumbra
