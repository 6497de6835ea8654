// Linear blend of two BSDFs: f = (1 - w) f_0 + w f_1 with w = weight(si) in [0, 1].
// Sampling picks BSDF 1 with probability w (else BSDF 0); a non-delta sample is then weighted by the mixture
// eval / pdf (one-sample MIS over the two children, consistent with pdf()); a delta sample keeps the child's weight.
//
// Mitsuba 3 parameters (src/bsdfs/blendbsdf.cpp):
//   weight        float|texture   (required)   blending weight: 0 = first BSDF, 1 = second
//   (nested bsdf) bsdf            (two)        the two BSDFs to blend
#include "scene/bsdfs/bsdfs.h"

namespace penumbra {

class BlendBSDF final : public BSDFBase<BlendBSDF> {
public:
    BlendBSDF(TexturePtr weight, BSDFPtr a, BSDFPtr b) : weight_(std::move(weight)), bsdf_{std::move(a), std::move(b)} {
        flags_ = bsdf_[0]->flags() | bsdf_[1]->flags();
    }
    template <typename T> Color3<T> eval_t(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        const T w = weight(si);
        return bsdf_[0]->eval(ctx, si, wo) * (T(1) - w) + bsdf_[1]->eval(ctx, si, wo) * w;
    }
    template <typename T> T pdf_t(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        const T w = weight(si);
        return bsdf_[0]->pdf(ctx, si, wo) * (T(1) - w) + bsdf_[1]->pdf(ctx, si, wo) * w;
    }
    template <typename T>
    Color3<T> delta_weight_t(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        const T w = weight(si);
        return bsdf_[0]->delta_weight(ctx, si, wo) * (T(1) - w) + bsdf_[1]->delta_weight(ctx, si, wo) * w;
    }
    std::pair<BSDFSample, Color3f> sample(const BSDFContext& ctx, const SurfaceInteraction3f& si, float u1,
                                          const Vec2f& u2) const override {
        const float w = weight(si);
        const int i = u1 < w ? 1 : 0;
        const float prob = i == 1 ? w : 1.f - w;
        const float u_rescaled = i == 1 ? u1 / w : (u1 - w) / (1.f - w);
        auto [bs, weight_child] = bsdf_[i]->sample(ctx, si, std::min(u_rescaled, 0.99999994f), u2);
        if (bs.pdf == 0.f || is_black(weight_child)) return {bs, Color3f(0.f)};
        if (bs.sampled_type & BSDFDelta) {
            bs.pdf *= prob;
            return {bs, weight_child};
        }
        bs.pdf = pdf_t<float>(ctx, si, bs.wo);
        if (!(bs.pdf > 0.f)) return {bs, Color3f(0.f)};
        return {bs, eval_t<float>(ctx, si, bs.wo) / bs.pdf};
    }
    Color3f eval_diffuse_reflectance(const SurfaceInteraction3f& si) const override {
        const float w = weight(si);
        return bsdf_[0]->eval_diffuse_reflectance(si) * (1.f - w) + bsdf_[1]->eval_diffuse_reflectance(si) * w;
    }

    // Differential lobes (paper 002 §4.1). Which parameter drives the lobe at si, in this order: the weight,
    // when it is enabled and both children are smooth: ∂f/∂w = f_1 − f_0, so the positive part is sampled from
    // child 1 and the negative part from child 0 (each sign chosen with probability 1/2 by the caller, so that
    // p_∂f = (p_0 + p_1) / 2); otherwise the lobe of the first child that has one for an enabled parameter
    // (∂f/∂θ = w ∂f_i/∂θ). Without any enabled parameter the weight lobe is used (for sampling tests).
    bool has_differential_lobe(const SurfaceInteraction3f& si) const override { return lobe(si, true) != Lobe::None; }
    BSDFSample sample_differential(const BSDFContext& ctx, const SurfaceInteraction3f& si, int sign, float u1,
                                   const Vec2f& u2) const override {
        const Lobe l = lobe(si, false);
        if (l == Lobe::Child0 || l == Lobe::Child1)
            return bsdf_[l == Lobe::Child1 ? 1 : 0]->sample_differential(ctx, si, sign, u1, u2);
        if (l == Lobe::None) return {};
        const BSDF& child = *bsdf_[sign > 0 ? 1 : 0];
        BSDFSample bs = child.sample(ctx, si, u1, u2).first;
        if (bs.pdf == 0.f || (bs.sampled_type & BSDFDelta)) return {};
        bs.pdf = child.pdf(ctx, si, bs.wo);
        return bs;
    }
    float pdf_differential(const BSDFContext& ctx, const SurfaceInteraction3f& si, int sign, const Vec3f& wo) const override {
        const Lobe l = lobe(si, false);
        if (l == Lobe::Child0 || l == Lobe::Child1)
            return bsdf_[l == Lobe::Child1 ? 1 : 0]->pdf_differential(ctx, si, sign, wo);
        if (l == Lobe::None) return 0.f;
        return bsdf_[sign > 0 ? 1 : 0]->pdf(ctx, si, wo);
    }

    void traverse(ParamVisitor& v) override {
        v.put_object("weight", weight_.get());
        v.put_object("bsdf_0", bsdf_[0].get());
        v.put_object("bsdf_1", bsdf_[1].get());
    }

private:
    template <typename T> T weight(const SurfaceInteraction<T>& si) const { return clamp(weight_->eval_1(si), 0.f, 1.f); }
    enum class Lobe { None, Weight, Child0, Child1 };
    // `enabled_only`: None unless the lobe's parameter is enabled; otherwise fall back to the weight lobe.
    Lobe lobe(const SurfaceInteraction3f& si, bool enabled_only) const {
        const bool smooth = !bsdf_[0]->has(BSDFDelta) && !bsdf_[1]->has(BSDFDelta);
        const bool weight_enabled = !weight_->eval_1(constant_interaction(si)).is_constant();
        if (weight_enabled) return smooth ? Lobe::Weight : Lobe::None;
        if (bsdf_[0]->has_differential_lobe(si)) return Lobe::Child0;
        if (bsdf_[1]->has_differential_lobe(si)) return Lobe::Child1;
        return enabled_only || !smooth ? Lobe::None : Lobe::Weight;
    }
    TexturePtr weight_;
    BSDFPtr bsdf_[2];
};

BSDFPtr make_blendbsdf(TexturePtr weight, BSDFPtr first, BSDFPtr second) {
    return std::make_shared<BlendBSDF>(std::move(weight), std::move(first), std::move(second));
}

BSDFPtr load_blendbsdf(const Properties& props) {
    if (!props.has("weight")) props.raise("weight", "blendbsdf requires a \"weight\" (float or texture)");
    TexturePtr weight = props.get_texture("weight");
    const auto children = nested_bsdfs(props);
    if (children.size() != 2)
        throw LoadError(props.location(), "blendbsdf: expected exactly two nested BSDFs, got " + std::to_string(children.size()));
    return make_blendbsdf(weight, children[0], children[1]);
}

} // namespace penumbra
