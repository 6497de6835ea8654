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
#define PENUMBRA_BSDF_METHODS(T)                                                                             \
    virtual Color3<T> eval(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const = 0; \
    virtual T pdf(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const = 0;
    PENUMBRA_FOR_EACH_SCALAR(PENUMBRA_BSDF_METHODS)
#undef PENUMBRA_BSDF_METHODS
    // Diffuse reflectance (the `albedo` AOV); zero for non-diffuse materials.
    virtual Color3f eval_diffuse_reflectance(const SurfaceInteraction3f&) const { return Color3f(0.f); }
    // Opacity of `mask`-like BSDFs is handled through Null sampling; nothing else is special.

protected:
    uint32_t flags_ = 0;
};

// CRTP helper: a BSDF implements `template <typename T> Color3<T> eval_t(ctx, si, wo) const` and `pdf_t`.
template <typename Derived> class BSDFBase : public BSDF {
public:
#define PENUMBRA_BSDF_IMPL(T)                                                                                \
    Color3<T> eval(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const override { \
        return static_cast<const Derived*>(this)->template eval_t<T>(ctx, si, wo);                           \
    }                                                                                                        \
    T pdf(const BSDFContext& ctx, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const override {       \
        return static_cast<const Derived*>(this)->template pdf_t<T>(ctx, si, wo);                            \
    }
    PENUMBRA_FOR_EACH_SCALAR(PENUMBRA_BSDF_IMPL)
#undef PENUMBRA_BSDF_IMPL
};

} // namespace penumbra
