// Smooth dielectric interface: specular reflection with probability F and refraction (Snell's law) with
// probability 1 - F; refracted radiance is scaled by eta_ti^2 in radiance mode (solid-angle compression).
//
// Mitsuba 3 parameters (src/bsdfs/dielectric.cpp):
//   int_ior                  float|string       "bk7" (1.5046)     interior index of refraction
//   ext_ior                  float|string       "air" (1.000277)   exterior index of refraction
//   specular_reflectance     spectrum|texture   1.0                multiplier of the reflected light
//   specular_transmittance   spectrum|texture   1.0                multiplier of the transmitted light
#include "core/fresnel.h"
#include "scene/bsdfs/bsdfs.h"

namespace penumbra {

class DielectricBSDF final : public BSDFBase<DielectricBSDF> {
public:
    DielectricBSDF(float eta, TexturePtr reflectance, TexturePtr transmittance)
        : eta_(eta), reflectance_(std::move(reflectance)), transmittance_(std::move(transmittance)) {
        flags_ = BSDFDeltaReflection | BSDFDeltaTransmission;
    }
    template <typename T> Color3<T> eval_t(const BSDFContext&, const SurfaceInteraction<T>&, const Vec3<T>&) const {
        return Color3<T>(T(0));
    }
    template <typename T> T pdf_t(const BSDFContext&, const SurfaceInteraction<T>&, const Vec3<T>&) const { return T(0); }
    // g = F R for the mirror lobe, (1 - F) T eta_ti^2 (radiance) for the refracted one.
    template <typename T>
    Color3<T> delta_weight_t(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        const auto fr = fresnel_dielectric(si.wi.z, eta_);
        if (si.wi.z * wo.z > T(0)) return reflectance_->eval(si) * fr.F;
        const T scale = ctx.mode == TransportMode::Radiance ? fr.eta_ti * fr.eta_ti : T(1);
        return transmittance_->eval(si) * ((T(1) - fr.F) * scale);
    }

    std::pair<BSDFSample, Color3f> sample(const BSDFContext& ctx, const SurfaceInteraction3f& si, float u1,
                                          const Vec2f&) const override {
        const auto fr = fresnel_dielectric(si.wi.z, eta_);
        BSDFSample bs;
        if (u1 <= fr.F) {
            bs.wo = Vec3f(-si.wi.x, -si.wi.y, si.wi.z);
            bs.pdf = fr.F;
            bs.sampled_type = BSDFDeltaReflection;
            return {bs, reflectance_->eval(si)};
        }
        // wo = -eta_ti wi_tangential + cos_t n (Snell's law).
        bs.wo = Vec3f(-fr.eta_ti * si.wi.x, -fr.eta_ti * si.wi.y, fr.cos_theta_t);
        bs.pdf = 1.f - fr.F;
        bs.eta = fr.eta_it;
        bs.sampled_type = BSDFDeltaTransmission;
        const float scale = ctx.mode == TransportMode::Radiance ? fr.eta_ti * fr.eta_ti : 1.f;
        return {bs, transmittance_->eval(si) * scale};
    }

    void traverse(ParamVisitor& v) override {
        v.put_object("specular_reflectance", reflectance_.get());
        v.put_object("specular_transmittance", transmittance_.get());
    }

private:
    float eta_;
    TexturePtr reflectance_, transmittance_;
};

BSDFPtr make_dielectric(float eta, TexturePtr specular_reflectance, TexturePtr specular_transmittance) {
    return std::make_shared<DielectricBSDF>(eta, std::move(specular_reflectance), std::move(specular_transmittance));
}

BSDFPtr load_dielectric(const Properties& props) {
    const DielectricParams p = parse_dielectric(props);
    return make_dielectric(p.eta, p.specular_reflectance, p.specular_transmittance);
}

} // namespace penumbra
