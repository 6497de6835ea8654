// Opacity mask: with probability 1 - opacity light passes through (Null lobe, wo = -wi, weight 1), otherwise it
// interacts with the nested BSDF: f = opacity * f_nested, pdf = opacity * pdf_nested.
//
// Mitsuba 3 parameters (src/bsdfs/mask.cpp):
//   opacity         float|texture   0.5     probability that light interacts with the nested BSDF
//   (nested bsdf)   bsdf            (one)   the masked BSDF
#include "scene/bsdfs/bsdfs.h"

namespace penumbra {

class MaskBSDF final : public BSDFBase<MaskBSDF> {
public:
    MaskBSDF(TexturePtr opacity, BSDFPtr nested) : opacity_(std::move(opacity)), nested_(std::move(nested)) {
        flags_ = nested_->flags() | BSDFNull;
    }
    template <typename T> Color3<T> eval_t(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        return nested_->eval(ctx, si, wo) * opacity(si);
    }
    template <typename T> T pdf_t(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        return nested_->pdf(ctx, si, wo) * opacity(si);
    }
    // The nested BSDF's delta lobes scaled by the opacity, and the pass-through (wo = -wi) by 1 - opacity.
    template <typename T>
    Color3<T> delta_weight_t(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        const T a = opacity(si);
        Color3<T> g = nested_->delta_weight(ctx, si, wo) * a;
        if (dot(wo, -si.wi) > T(1.f - 1e-5f)) g = g + Color3<T>(T(1) - a);
        return g;
    }
    std::pair<BSDFSample, Color3f> sample(const BSDFContext& ctx, const SurfaceInteraction3f& si, float u1,
                                          const Vec2f& u2) const override {
        const float a = opacity(si), null_prob = 1.f - a;
        if (u1 < null_prob) {
            BSDFSample bs;
            bs.wo = -si.wi;
            bs.pdf = null_prob;
            bs.sampled_type = BSDFNull;
            return {bs, Color3f(1.f)};
        }
        auto [bs, weight] = nested_->sample(ctx, si, std::min((u1 - null_prob) / a, 0.99999994f), u2);
        bs.pdf *= a;
        return {bs, weight};
    }
    Color3f eval_diffuse_reflectance(const SurfaceInteraction3f& si) const override {
        return nested_->eval_diffuse_reflectance(si);
    }

    void traverse(ParamVisitor& v) override {
        v.put_object("opacity", opacity_.get());
        v.put_object("nested_bsdf", nested_.get());
    }

private:
    template <typename T> T opacity(const SurfaceInteraction<T>& si) const { return clamp(opacity_->eval_1(si), 0.f, 1.f); }
    TexturePtr opacity_;
    BSDFPtr nested_;
};

BSDFPtr make_mask(TexturePtr opacity, BSDFPtr nested) { return std::make_shared<MaskBSDF>(std::move(opacity), std::move(nested)); }

BSDFPtr load_mask(const Properties& props) {
    TexturePtr opacity = props.get_texture("opacity", Color3f(0.5f));
    const auto children = nested_bsdfs(props);
    if (children.size() != 1)
        throw LoadError(props.location(), "mask: expected exactly one nested BSDF, got " + std::to_string(children.size()));
    return make_mask(opacity, children[0]);
}

} // namespace penumbra
