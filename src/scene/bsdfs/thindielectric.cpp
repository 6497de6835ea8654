// Thin dielectric slab: reflection and straight transmission (wo = -wi) with the interreflections between the
// two parallel interfaces summed: R' = R + T^2 R / (1 - R^2), T' = 1 - R'.
//
// Mitsuba 3 parameters (src/bsdfs/thindielectric.cpp):
//   int_ior                  float|string       "bk7" (1.5046)     interior index of refraction
//   ext_ior                  float|string       "air" (1.000277)   exterior index of refraction
//   specular_reflectance     spectrum|texture   1.0                multiplier of the reflected light
//   specular_transmittance   spectrum|texture   1.0                multiplier of the transmitted light
#include "core/fresnel.h"
#include "scene/bsdfs/bsdfs.h"

namespace penumbra {

class ThinDielectricBSDF final : public BSDFBase<ThinDielectricBSDF> {
public:
    ThinDielectricBSDF(float eta, TexturePtr reflectance, TexturePtr transmittance)
        : eta_(eta), reflectance_(std::move(reflectance)), transmittance_(std::move(transmittance)) {
        flags_ = BSDFDeltaReflection | BSDFNull;
    }
    template <typename T> Color3<T> eval_t(const BSDFContext&, const SurfaceInteraction<T>&, const Vec3<T>&) const {
        return Color3<T>(T(0));
    }
    template <typename T> T pdf_t(const BSDFContext&, const SurfaceInteraction<T>&, const Vec3<T>&) const { return T(0); }
    // g = R' reflectance for the mirror lobe, (1 - R') transmittance through the slab (R' with the internal
    // bounces, as sample()).
    template <typename T>
    Color3<T> delta_weight_t(const BSDFContext&, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        using std::abs;
        T R = fresnel_dielectric(abs(si.wi.z), eta_).F;
        const T t = T(1) - R;
        if (R < T(1)) R = R + t * t * R / (T(1) - R * R);
        if (si.wi.z * wo.z > T(0)) return reflectance_->eval(si) * R;
        return transmittance_->eval(si) * (T(1) - R);
    }

    std::pair<BSDFSample, Color3f> sample(const BSDFContext&, const SurfaceInteraction3f& si, float u1,
                                          const Vec2f&) const override {
        float R = fresnel_dielectric(std::abs(si.wi.z), eta_).F;
        const float T = 1.f - R;
        if (R < 1.f) R += T * T * R / (1.f - R * R);
        BSDFSample bs;
        if (u1 <= R) {
            bs.wo = Vec3f(-si.wi.x, -si.wi.y, si.wi.z);
            bs.pdf = R;
            bs.sampled_type = BSDFDeltaReflection;
            return {bs, reflectance_->eval(si)};
        }
        bs.wo = -si.wi;
        bs.pdf = 1.f - R;
        bs.sampled_type = BSDFNull;
        return {bs, transmittance_->eval(si)};
    }

    void traverse(ParamVisitor& v) override {
        v.put_object("specular_reflectance", reflectance_.get());
        v.put_object("specular_transmittance", transmittance_.get());
    }

private:
    float eta_;
    TexturePtr reflectance_, transmittance_;
};

BSDFPtr make_thindielectric(float eta, TexturePtr specular_reflectance, TexturePtr specular_transmittance) {
    return std::make_shared<ThinDielectricBSDF>(eta, std::move(specular_reflectance), std::move(specular_transmittance));
}

BSDFPtr load_thindielectric(const Properties& props) {
    const DielectricParams p = parse_dielectric(props);
    return make_thindielectric(p.eta, p.specular_reflectance, p.specular_transmittance);
}

} // namespace penumbra
