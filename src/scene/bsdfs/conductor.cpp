// Smooth conductor: perfect specular reflection weighted by the conductor Fresnel term F(cos_i; eta + i k).
//
// Mitsuba 3 parameters (src/bsdfs/conductor.cpp):
//   material               string             "none"   named conductor (Cu, Au, Ag, Al, Cr, ...); "none" = eta 0, k 1
//   eta, k                 spectrum|texture   0, 1     real and imaginary part of the IOR (instead of material)
//   specular_reflectance   spectrum|texture   1.0      multiplier of the reflected light
#include "core/fresnel.h"
#include "scene/bsdfs/bsdfs.h"

namespace penumbra {

class ConductorBSDF final : public BSDFBase<ConductorBSDF> {
public:
    ConductorBSDF(TexturePtr eta, TexturePtr k, TexturePtr specular)
        : eta_(std::move(eta)), k_(std::move(k)), specular_(std::move(specular)) {
        flags_ = BSDFDeltaReflection;
    }
    template <typename T> Color3<T> eval_t(const BSDFContext&, const SurfaceInteraction<T>&, const Vec3<T>&) const {
        return Color3<T>(T(0));
    }
    template <typename T> T pdf_t(const BSDFContext&, const SurfaceInteraction<T>&, const Vec3<T>&) const { return T(0); }
    // g = specular_reflectance F(cos_i) (the mirror lobe; paper 003 Eq. 19 with D the delta).
    template <typename T>
    Color3<T> delta_weight_t(const BSDFContext&, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        if (!(si.wi.z > T(0) && wo.z > T(0))) return Color3<T>(T(0));
        return specular_->eval(si) * fresnel_conductor(si.wi.z, eta_->eval(si), k_->eval(si));
    }
    // wo = mirror(wi), weight = specular_reflectance * F(cos_i).
    std::pair<BSDFSample, Color3f> sample(const BSDFContext&, const SurfaceInteraction3f& si, float,
                                          const Vec2f&) const override {
        BSDFSample bs;
        if (!(si.wi.z > 0.f)) return {bs, Color3f(0.f)};
        bs.wo = Vec3f(-si.wi.x, -si.wi.y, si.wi.z);
        bs.pdf = 1.f;
        bs.sampled_type = BSDFDeltaReflection;
        return {bs, specular_->eval(si) * fresnel_conductor(si.wi.z, eta_->eval(si), k_->eval(si))};
    }

    void traverse(ParamVisitor& v) override {
        v.put_object("eta", eta_.get());
        v.put_object("k", k_.get());
        v.put_object("specular_reflectance", specular_.get());
    }

private:
    TexturePtr eta_, k_, specular_;
};

BSDFPtr make_conductor(TexturePtr eta, TexturePtr k, TexturePtr specular_reflectance) {
    return std::make_shared<ConductorBSDF>(std::move(eta), std::move(k), std::move(specular_reflectance));
}

BSDFPtr load_conductor(const Properties& props) {
    TexturePtr eta, k;
    parse_conductor_ior(props, eta, k);
    return make_conductor(eta, k, props.get_texture("specular_reflectance", Color3f(1.f)));
}

} // namespace penumbra
