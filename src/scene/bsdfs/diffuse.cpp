// Ideal diffuse (Lambertian) reflection: f = R / pi, cosine-weighted sampling.
//
// Mitsuba 3 parameters (src/bsdfs/diffuse.cpp):
//   reflectance   spectrum|texture   0.5   diffuse reflectance R
#include "core/warp.h"
#include "scene/bsdfs/bsdfs.h"

namespace penumbra {

class DiffuseBSDF final : public BSDFBase<DiffuseBSDF> {
public:
    explicit DiffuseBSDF(TexturePtr reflectance) : reflectance_(std::move(reflectance)) { flags_ = BSDFDiffuseReflection; }

    // eval = R / pi * cos(theta_o), both directions on the front side.
    template <typename T> Color3<T> eval_t(const BSDFContext&, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        if (!(si.wi.z > T(0) && wo.z > T(0))) return Color3<T>(T(0));
        return reflectance_->eval(si) * (wo.z * T(InvPi));
    }
    template <typename T> T pdf_t(const BSDFContext&, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        if (!(si.wi.z > T(0) && wo.z > T(0))) return T(0);
        return warp::square_to_cosine_hemisphere_pdf(wo);
    }
    std::pair<BSDFSample, Color3f> sample(const BSDFContext&, const SurfaceInteraction3f& si, float,
                                          const Vec2f& u) const override {
        BSDFSample bs;
        if (!(si.wi.z > 0.f)) return {bs, Color3f(0.f)};
        bs.wo = warp::square_to_cosine_hemisphere(u);
        bs.pdf = warp::square_to_cosine_hemisphere_pdf(bs.wo);
        bs.sampled_type = BSDFDiffuseReflection;
        if (!(bs.pdf > 0.f)) return {bs, Color3f(0.f)};
        return {bs, reflectance_->eval(si)}; // (R/pi cos) / (cos/pi)
    }
    Color3f eval_diffuse_reflectance(const SurfaceInteraction3f& si) const override { return reflectance_->eval(si); }

    void traverse(ParamVisitor& v) override {
        v.put_object("reflectance", reflectance_.get());
    }

private:
    TexturePtr reflectance_;
};

BSDFPtr make_diffuse(TexturePtr reflectance) { return std::make_shared<DiffuseBSDF>(std::move(reflectance)); }

BSDFPtr load_diffuse(const Properties& props) { return make_diffuse(props.get_texture("reflectance", Color3f(0.5f))); }

} // namespace penumbra
