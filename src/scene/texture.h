// Textures: spatially varying parameters evaluated at surface interactions.
#pragma once
#include "core/scalar.h"
#include "scene/interaction.h"
#include "scene/object.h"

#include <functional>
#include <memory>

namespace penumbra {

class Texture : public Object {
public:
    ObjectKind kind() const override { return ObjectKind::Texture; }
#define PENUMBRA_TEXTURE_METHODS(T)                                                                          \
    virtual Color3<T> eval(const SurfaceInteraction<T>& si) const = 0;                                       \
    /* Single-channel value (alpha, weight, height): channel mean; a bitmap's luminance. */                  \
    virtual T eval_1(const SurfaceInteraction<T>& si) const = 0;
    PENUMBRA_FOR_EACH_SCALAR(PENUMBRA_TEXTURE_METHODS)
#undef PENUMBRA_TEXTURE_METHODS
    // Gradient of eval_1 with respect to (u, v) (Mitsuba's eval_1_grad, used by `bumpmap`); zero for
    // textures that are constant or piecewise constant in uv.
#define PENUMBRA_TEXTURE_GRAD(T)                                                                             \
    virtual Vec2<T> eval_1_grad(const SurfaceInteraction<T>&) const { return Vec2<T>(T(0), T(0)); }
    PENUMBRA_FOR_EACH_SCALAR(PENUMBRA_TEXTURE_GRAD)
#undef PENUMBRA_TEXTURE_GRAD
    // Average value over the texture's domain.
    virtual Color3f mean() const = 0;
    virtual bool is_constant() const { return false; }
    // Whether the value is continuous in uv (a checkerboard or a nearest-neighbour bitmap jumps).
    virtual bool is_continuous() const { return true; }
    // Texels along u and v (Mitsuba's resolution(): 1 x 1 for textures that are not images).
    virtual Vec2i resolution() const { return {1, 1}; }
};

// CRTP helper: a texture implements `template <typename T> Color3<T> eval_t(const SurfaceInteraction<T>&) const`.
template <typename Derived> class TextureBase : public Texture {
public:
#define PENUMBRA_TEXTURE_IMPL(T)                                                                             \
    Color3<T> eval(const SurfaceInteraction<T>& si) const override {                                        \
        return static_cast<const Derived*>(this)->template eval_t<T>(si);                                    \
    }                                                                                                        \
    T eval_1(const SurfaceInteraction<T>& si) const override {                                              \
        const Color3<T> c = eval(si);                                                                        \
        return (c.x + c.y + c.z) * T(1.f / 3.f);                                                             \
    }
    PENUMBRA_FOR_EACH_SCALAR(PENUMBRA_TEXTURE_IMPL)
#undef PENUMBRA_TEXTURE_IMPL
};

// Whether a texture nested in `object` (its BSDF's, its emitter's, theirs...) satisfies `match`.
bool has_texture(Object& object, const std::function<bool(const Texture&)>& match);

// A texture with one value everywhere (what rgb/float/spectrum parameters become).
std::shared_ptr<Texture> make_constant_texture(const Color3f& value);

} // namespace penumbra
