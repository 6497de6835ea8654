// Shared by `normalmap` and `bumpmap`: a nested BSDF evaluated in a perturbed shading frame. The perturbed
// frame is given in the local coordinates of the original shading frame; wi and wo are carried into it, and a
// direction that changes side between the two frames is rejected (Mitsuba 3, src/bsdfs/normalmap.cpp and
// bumpmap.cpp).
#pragma once
#include "scene/bsdfs/bsdfs.h"

namespace penumbra {

// The frame with normal n (local coordinates, unit) whose tangent is the original tangent (1, 0, 0)
// Gram-Schmidt orthogonalized against n (coordinate_system(n) if they are parallel).
template <typename T> Frame<T> frame_about_normal(const Vec3<T>& n) {
    const Vec3<T> s = Vec3<T>(T(1), T(0), T(0)) - n * n.x;
    const T length = norm(s);
    if (!(length > T(1e-6f))) return Frame<T>(n);
    const Vec3<T> s_unit = s / length;
    return Frame<T>(s_unit, cross(n, s_unit), n);
}

// CRTP base: Derived provides `template <typename T> Frame<T> frame(const SurfaceInteraction<T>&) const`.
template <typename Derived> class PerturbedFrameBSDF : public BSDFBase<Derived> {
  public:
    explicit PerturbedFrameBSDF(BSDFPtr nested) : nested_(std::move(nested)) {
        this->flags_ = nested_->flags();
    }

    template <typename T>
    Color3<T> eval_t(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        const Frame<T> f = derived().template frame<T>(si);
        const Vec3<T> wo_p = f.to_local(wo);
        if (!(wo.z * wo_p.z > T(0))) return Color3<T>(T(0));
        return nested_->eval(ctx, perturbed(si, f), wo_p);
    }
    template <typename T>
    T pdf_t(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        const Frame<T> f = derived().template frame<T>(si);
        const Vec3<T> wo_p = f.to_local(wo);
        if (!(wo.z * wo_p.z > T(0))) return T(0);
        return nested_->pdf(ctx, perturbed(si, f), wo_p);
    }
    template <typename T>
    Color3<T> delta_weight_t(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        const Frame<T> f = derived().template frame<T>(si);
        const Vec3<T> wo_p = f.to_local(wo);
        if (!(wo.z * wo_p.z > T(0))) return Color3<T>(T(0));
        return nested_->delta_weight(ctx, perturbed(si, f), wo_p);
    }
    std::pair<BSDFSample, Color3f> sample(const BSDFContext& ctx, const SurfaceInteraction3f& si, float u1,
                                          const Vec2f& u2) const override {
        const Frame3f f = derived().template frame<float>(si);
        auto [bs, weight] = nested_->sample(ctx, perturbed(si, f), u1, u2);
        if (is_black(weight)) return {bs, Color3f(0.f)};
        const Vec3f wo = f.to_world(bs.wo);
        if (!(bs.wo.z * wo.z > 0.f)) return {bs, Color3f(0.f)};
        bs.wo = wo;
        return {bs, weight};
    }
    Color3f eval_diffuse_reflectance(const SurfaceInteraction3f& si) const override {
        return nested_->eval_diffuse_reflectance(si);
    }

  protected:
    const BSDFPtr& nested() const { return nested_; }

  private:
    const Derived& derived() const { return static_cast<const Derived&>(*this); }
    // The interaction seen by the nested BSDF: the perturbed frame in world space, wi in its coordinates.
    template <typename T>
    static SurfaceInteraction<T> perturbed(const SurfaceInteraction<T>& si, const Frame<T>& f) {
        SurfaceInteraction<T> p = si;
        p.sh_frame = Frame<T>(si.to_world(f.s), si.to_world(f.t), si.to_world(f.n));
        p.wi = f.to_local(si.wi);
        return p;
    }
    BSDFPtr nested_;
};

} // namespace penumbra
