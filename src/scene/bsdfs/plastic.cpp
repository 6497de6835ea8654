// Smooth plastic: a specular dielectric coating (Fresnel F) over a diffuse base, with internal interreflection
// through the coating's average internal reflectance Fdr_int:
//   diffuse part  f cos_o = R / (1 - Fdr_int) (or R / (1 - R Fdr_int) if nonlinear) (1-F_i)(1-F_o) / (pi eta^2) cos_o
//   specular part a delta reflection of weight specular_reflectance * F_i.
// Lobe selection: specular with probability F_i w_s / (F_i w_s + (1-F_i)(1-w_s)), w_s = s_mean / (d_mean + s_mean).
//
// Mitsuba 3 parameters (src/bsdfs/plastic.cpp):
//   int_ior                float|string       "polypropylene" (1.49)   interior index of refraction
//   ext_ior                float|string       "air" (1.000277)         exterior index of refraction
//   diffuse_reflectance    spectrum|texture   0.5                      base reflectance
//   specular_reflectance   spectrum|texture   1.0                      multiplier of the specular lobe
//   nonlinear              boolean            false                    account for color shifts by interreflection
#include "core/fresnel.h"
#include "core/warp.h"
#include "scene/bsdfs/bsdfs.h"

namespace penumbra {

class PlasticBSDF final : public BSDFBase<PlasticBSDF> {
public:
    PlasticBSDF(float eta, TexturePtr diffuse, TexturePtr specular, bool nonlinear)
        : eta_(eta), inv_eta2_(1.f / (eta * eta)), diffuse_(std::move(diffuse)), specular_(std::move(specular)),
          nonlinear_(nonlinear), fdr_int_(fresnel_diffuse_reflectance(1.f / eta)) {
        const float d = luminance_mean(diffuse_), s = luminance_mean(specular_);
        specular_weight_ = s / (d + s);
        flags_ = BSDFDeltaReflection | BSDFDiffuseReflection;
    }

    template <typename T> Color3<T> eval_t(const BSDFContext&, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        const T ci = si.wi.z, co = wo.z;
        if (!(ci > T(0) && co > T(0))) return Color3<T>(T(0));
        const T fi = fresnel_dielectric(ci, eta_).F, fo = fresnel_dielectric(co, eta_).F;
        return diffuse_term(si) * (T(InvPi * inv_eta2_) * co * (T(1) - fi) * (T(1) - fo));
    }
    template <typename T> T pdf_t(const BSDFContext&, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        if (!(si.wi.z > T(0) && wo.z > T(0))) return T(0);
        const T fi = fresnel_dielectric(si.wi.z, eta_).F;
        return (T(1) - prob_specular(fi)) * warp::square_to_cosine_hemisphere_pdf(wo);
    }
    // The coating's mirror lobe: g = specular_reflectance F(cos_i).
    template <typename T>
    Color3<T> delta_weight_t(const BSDFContext&, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        if (!(si.wi.z > T(0) && wo.z > T(0))) return Color3<T>(T(0));
        return specular_->eval(si) * fresnel_dielectric(si.wi.z, eta_).F;
    }
    std::pair<BSDFSample, Color3f> sample(const BSDFContext& ctx, const SurfaceInteraction3f& si, float u1,
                                          const Vec2f& u2) const override {
        BSDFSample bs;
        if (!(si.wi.z > 0.f)) return {bs, Color3f(0.f)};
        const float fi = fresnel_dielectric(si.wi.z, eta_).F;
        const float ps = prob_specular(fi);
        if (u1 < ps) {
            bs.wo = Vec3f(-si.wi.x, -si.wi.y, si.wi.z);
            bs.pdf = ps;
            bs.sampled_type = BSDFDeltaReflection;
            return {bs, specular_->eval(si) * (fi / ps)};
        }
        bs.wo = warp::square_to_cosine_hemisphere(u2);
        bs.sampled_type = BSDFDiffuseReflection;
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
    static float luminance_mean(const TexturePtr& t) {
        const Color3f m = t->mean();
        return (m.x + m.y + m.z) / 3.f;
    }
    template <typename T> T prob_specular(const T& fi) const {
        const T s = fi * T(specular_weight_), d = (T(1) - fi) * T(1.f - specular_weight_);
        return s / (s + d);
    }
    template <typename T> Color3<T> diffuse_term(const SurfaceInteraction<T>& si) const {
        const Color3<T> R = diffuse_->eval(si);
        if (nonlinear_) return R / (Color3<T>(T(1)) - R * T(fdr_int_));
        return R / T(1.f - fdr_int_);
    }
    float eta_, inv_eta2_;
    TexturePtr diffuse_, specular_;
    bool nonlinear_;
    float fdr_int_, specular_weight_ = 0.5f;
};

BSDFPtr make_plastic(float eta, TexturePtr diffuse_reflectance, TexturePtr specular_reflectance, bool nonlinear) {
    return std::make_shared<PlasticBSDF>(eta, std::move(diffuse_reflectance), std::move(specular_reflectance), nonlinear);
}

BSDFPtr load_plastic(const Properties& props) {
    const PlasticParams p = parse_plastic(props);
    return make_plastic(p.eta, p.diffuse_reflectance, p.specular_reflectance, p.nonlinear);
}

} // namespace penumbra
