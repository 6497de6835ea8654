// Two-sided adapter: when wi is on the back side, both directions are mirrored (z -> -z) and the back BSDF
// (or the front one if only one is given) is evaluated on the front side.
//
// Mitsuba 3 parameters (src/bsdfs/twosided.cpp):
//   (nested bsdf)   bsdf   (one or two)   front BSDF, and optionally a different back BSDF
#include "scene/bsdfs/bsdfs.h"

namespace penumbra {

class TwoSidedBSDF final : public BSDFBase<TwoSidedBSDF> {
public:
    TwoSidedBSDF(BSDFPtr front, BSDFPtr back) : front_(std::move(front)), back_(back ? std::move(back) : front_) {
        flags_ = front_->flags() | back_->flags();
    }
    template <typename T> Color3<T> eval_t(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        if (si.wi.z > T(0)) return front_->eval(ctx, si, wo);
        const SurfaceInteraction<T> si_back = mirrored(si);
        return back_->eval(ctx, si_back, Vec3<T>(wo.x, wo.y, -wo.z));
    }
    template <typename T> T pdf_t(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        if (si.wi.z > T(0)) return front_->pdf(ctx, si, wo);
        const SurfaceInteraction<T> si_back = mirrored(si);
        return back_->pdf(ctx, si_back, Vec3<T>(wo.x, wo.y, -wo.z));
    }
    template <typename T>
    Color3<T> delta_weight_t(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        if (si.wi.z > T(0)) return front_->delta_weight(ctx, si, wo);
        return back_->delta_weight(ctx, mirrored(si), Vec3<T>(wo.x, wo.y, -wo.z));
    }
    std::pair<BSDFSample, Color3f> sample(const BSDFContext& ctx, const SurfaceInteraction3f& si, float u1,
                                          const Vec2f& u2) const override {
        if (si.wi.z > 0.f) return front_->sample(ctx, si, u1, u2);
        auto result = back_->sample(ctx, mirrored(si), u1, u2);
        result.first.wo.z = -result.first.wo.z;
        return result;
    }
    Color3f eval_diffuse_reflectance(const SurfaceInteraction3f& si) const override {
        return si.wi.z > 0.f ? front_->eval_diffuse_reflectance(si) : back_->eval_diffuse_reflectance(mirrored(si));
    }

    void traverse(ParamVisitor& v) override {
        v.put_object("brdf_0", front_.get());
        if (back_) v.put_object("brdf_1", back_.get());
    }

private:
    template <typename T> static SurfaceInteraction<T> mirrored(const SurfaceInteraction<T>& si) {
        SurfaceInteraction<T> s = si;
        s.wi.z = -s.wi.z;
        return s;
    }
    BSDFPtr front_, back_;
};

BSDFPtr make_twosided(BSDFPtr front, BSDFPtr back) { return std::make_shared<TwoSidedBSDF>(std::move(front), std::move(back)); }

BSDFPtr load_twosided(const Properties& props) {
    const auto children = nested_bsdfs(props);
    if (children.empty() || children.size() > 2)
        throw LoadError(props.location(), "twosided: expected one or two nested BSDFs, got " + std::to_string(children.size()));
    for (const auto& c : children)
        if (c->has(BSDFTransmission))
            throw LoadError(c->location.file.empty() ? props.location() : c->location,
                            "twosided: only BSDFs without transmission can be nested (got " + c->plugin + ")");
    return make_twosided(children[0], children.size() == 2 ? children[1] : nullptr);
}

} // namespace penumbra
