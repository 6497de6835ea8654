// BSDF interface (Mitsuba 3 conventions): directions are in the local shading frame and point away from
// the surface; `si.wi` points toward the previous vertex; eval() returns f(wi, wo) * |cos(theta_o)|.
// eval()/pdf() are templated on the scalar type (one physics code path for rendering and derivatives);
// sampling is done on detached (float) values.
#pragma once
#include "core/scalar.h"
#include "scene/interaction.h"
#include "scene/object.h"

#include <utility>

namespace penumbra {

enum BSDFFlags : uint32_t {
    BSDFNone = 0,
    BSDFNull = 1u << 0,
    BSDFDiffuseReflection = 1u << 1,
    BSDFDiffuseTransmission = 1u << 2,
    BSDFGlossyReflection = 1u << 3,
    BSDFGlossyTransmission = 1u << 4,
    BSDFDeltaReflection = 1u << 5,
    BSDFDeltaTransmission = 1u << 6,
    BSDFReflection = BSDFDiffuseReflection | BSDFGlossyReflection | BSDFDeltaReflection,
    BSDFTransmission = BSDFNull | BSDFDiffuseTransmission | BSDFGlossyTransmission | BSDFDeltaTransmission,
    BSDFDiffuse = BSDFDiffuseReflection | BSDFDiffuseTransmission,
    BSDFGlossy = BSDFGlossyReflection | BSDFGlossyTransmission,
    BSDFSmooth = BSDFDiffuse | BSDFGlossy,
    BSDFDelta = BSDFNull | BSDFDeltaReflection | BSDFDeltaTransmission,
    BSDFAll = BSDFDiffuse | BSDFGlossy | BSDFDelta,
};

// Radiance: tracing from the camera; Importance: tracing from emitters (adjoint transport, refraction scaling differs).
enum class TransportMode { Radiance, Importance };

struct BSDFContext {
    TransportMode mode = TransportMode::Radiance;
};

struct BSDFSample {
    Vec3f wo;                      // sampled direction (local)
    float pdf = 0.f;               // solid-angle density (1 for delta lobes chosen with certainty)
    float eta = 1.f;               // relative index of refraction along the sampled direction
    uint32_t sampled_type = 0;     // the BSDFFlags lobe that was sampled
};

class BSDF : public Object {
public:
    ObjectKind kind() const override { return ObjectKind::BSDF; }
    uint32_t flags() const { return flags_; }
    bool has(uint32_t f) const { return (flags_ & f) != 0; }

    // Returns the sample and its weight eval(wo)/pdf (zero weight = failed sample).
    virtual std::pair<BSDFSample, Color3f> sample(const BSDFContext& ctx, const SurfaceInteraction3f& si,
                                                  float sample1, const Vec2f& sample2) const = 0;
    // delta_weight(): the smooth factor g of the delta lobe that scatters si.wi into wo (paper 003 §4.2.2,
    // Eq. 16: f = g · h with h the lobe's delta, constant on a manifold that keeps the half vector): the lobe's
    // sampled weight times its selection probability (dielectric: F R or (1 − F) T η², conductor: F R, null: 1),
    // evaluated at any wi, so that its derivative follows wi's; zero when no delta lobe leads from wi to wo.
#define PENUMBRA_BSDF_METHODS(T)                                                                             \
    virtual Color3<T> eval(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const = 0; \
    virtual T pdf(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const = 0;          \
    virtual Color3<T> delta_weight(const BSDFContext&, const SurfaceInteraction<T>&, const Vec3<T>&) const {     \
        return Color3<T>(T(0));                                                                              \
    }
    PENUMBRA_FOR_EACH_SCALAR(PENUMBRA_BSDF_METHODS)
#undef PENUMBRA_BSDF_METHODS
    // Diffuse reflectance (the `albedo` AOV); zero for non-diffuse materials.
    virtual Color3f eval_diffuse_reflectance(const SurfaceInteraction3f&) const { return Color3f(0.f); }

    // Differential BSDF sampling (paper 002 §4.1): densities for the positive (sign = +1) and negative (sign = -1)
    // parts of ∂(f cos)/∂θ for one parameter θ of this BSDF (single-signed decompositions, Belhe et al. 2024).
    // Each signed density is normalized over the sphere (samples that leave the valid hemisphere fail: weight
    // and pdf 0). They are sampling-only approximations of the derivative; its value always comes from eval()
    // with Var. has_differential_lobe() tells whether the lobe's parameter is enabled for differentiation at si
    // (it evaluates the parameter as Var: it may record nodes on the current thread's tape). BSDFs without a
    // lobe keep the defaults; the estimators then use BSDF sampling at that vertex.
    virtual bool has_differential_lobe(const SurfaceInteraction3f&) const { return false; }
    virtual BSDFSample sample_differential(const BSDFContext&, const SurfaceInteraction3f&, int /*sign*/, float /*sample1*/,
                                           const Vec2f& /*sample2*/) const {
        return {};
    }
    virtual float pdf_differential(const BSDFContext&, const SurfaceInteraction3f&, int /*sign*/, const Vec3f& /*wo*/) const {
        return 0.f;
    }
    // Opacity of `mask`-like BSDFs is handled through Null sampling; nothing else is special.

protected:
    uint32_t flags_ = 0;
};

// The float interaction as Var constants: lets a BSDF evaluate one of its textures as Var to see whether it
// depends on an enabled parameter (has_differential_lobe()).
inline SurfaceInteraction<Var> constant_interaction(const SurfaceInteraction3f& si) {
    SurfaceInteraction<Var> v;
    v.t = Var(si.t);
    v.p = Vec3<Var>(si.p);
    v.n = Vec3<Var>(si.n);
    v.sh_frame = Frame<Var>(Vec3<Var>(si.sh_frame.s), Vec3<Var>(si.sh_frame.t), Vec3<Var>(si.sh_frame.n));
    v.uv = Vec2<Var>(Var(si.uv.x), Var(si.uv.y));
    v.wi = Vec3<Var>(si.wi);
    v.bary = si.bary;
    v.shape = si.shape;
    v.prim_index = si.prim_index;
    return v;
}

// The direction of the delta lobe sampled in `bs` (at the reference incident direction wi0, local) for the
// incident direction wi (local, on the tape): the lobe keeps its generalized half vector h ∝ wi0 + η wo0
// fixed in the shading frame (paper 003 Eq. 3; η = bs.eta across a refraction, 1 for a reflection), so
//   reflection:  wo = 2 (wi · h) h − wi;
//   refraction:  wo = h (c η_ti + cos θ_t) − wi η_ti, with c = wi · h, η_ti = 1 / η and
//                cos θ_t = −sign(c) √(1 − η_ti² (1 − c²));
//   null lobe:   wo = −wi (the ray goes on).
template <typename T> Vec3<T> delta_direction(const Vec3<T>& wi, const Vec3f& wi0, const BSDFSample& bs) {
    const bool reflection = (bs.sampled_type & BSDFDeltaReflection) != 0;
    const float eta = reflection ? 1.f : bs.eta;
    const Vec3f sum = wi0 + bs.wo * eta;
    if (!reflection && squared_norm(sum) < 1e-10f) return -wi;
    const Vec3<T> h(normalize(sum));
    const T c = dot(wi, h);
    if (reflection) return h * (T(2) * c) - wi;
    const T eta_ti = T(1.f / eta);
    const T cos_t2 = T(1) - eta_ti * eta_ti * (T(1) - c * c);
    const T cos_t = detach(c) >= 0.f ? -safe_sqrt(cos_t2) : safe_sqrt(cos_t2);
    return h * (c * eta_ti + cos_t) - wi * eta_ti;
}

// CRTP helper: a BSDF implements `template <typename T> Color3<T> eval_t(ctx, si, wo) const` and `pdf_t`, and a
// BSDF with delta lobes `delta_weight_t` (without one, delta_weight() is zero).
template <typename Derived> class BSDFBase : public BSDF {
public:
#define PENUMBRA_BSDF_IMPL(T)                                                                                \
    Color3<T> eval(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const override { \
        return static_cast<const Derived*>(this)->template eval_t<T>(ctx, si, wo);                           \
    }                                                                                                        \
    T pdf(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const override {       \
        return static_cast<const Derived*>(this)->template pdf_t<T>(ctx, si, wo);                            \
    }                                                                                                        \
    Color3<T> delta_weight(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo)        \
        const override {                                                                                     \
        const auto* d = static_cast<const Derived*>(this);                                                   \
        if constexpr (requires { d->template delta_weight_t<T>(ctx, si, wo); })                              \
            return d->template delta_weight_t<T>(ctx, si, wo);                                               \
        else                                                                                                 \
            return Color3<T>(T(0));                                                                          \
    }
    PENUMBRA_FOR_EACH_SCALAR(PENUMBRA_BSDF_IMPL)
#undef PENUMBRA_BSDF_IMPL
};

} // namespace penumbra
