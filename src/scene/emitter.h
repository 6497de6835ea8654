// Emitter interface: area, point, spot, directional, constant (environment) and envmap lights.
#pragma once
#include "core/scalar.h"
#include "core/transform.h"
#include "scene/interaction.h"
#include "scene/object.h"

#include <memory>
#include <utility>

namespace penumbra {

class Medium;
class Shape;
struct TriangleMesh;
struct BoundingSphere {
    Vec3f center;
    float radius = 0.f;
};
// The sphere around a mesh's axis-aligned bounding box (centred on the box, radius half its diagonal).
BoundingSphere bounding_sphere(const TriangleMesh& mesh);

enum EmitterFlags : uint32_t {
    EmitterDeltaPosition = 1u << 0,  // point, spot, projector
    EmitterDeltaDirection = 1u << 1, // directional
    EmitterInfinite = 1u << 2,       // constant, envmap, directional
    EmitterSurface = 1u << 3,        // area
};

class Emitter : public Object {
public:
    ObjectKind kind() const override { return ObjectKind::Emitter; }
    uint32_t flags() const { return flags_; }
    bool is_delta() const { return (flags_ & (EmitterDeltaPosition | EmitterDeltaDirection)) != 0; }
    bool is_infinite() const { return (flags_ & EmitterInfinite) != 0; }

    // Next-event estimation: sample a point of the emitter as seen from `ref`. Returns the sample and the weight
    // L_e(p -> ref) / pdf (solid angle; for area lights the cosine at the emitter is in the pdf conversion).
    // Visibility is not tested. A zero weight means the sample failed (e.g. ref behind an area light).
    virtual std::pair<DirectionSample3f, Color3f> sample_direction(const Interaction3f& ref, const Vec2f& u) const = 0;

    // Light tracing: sample an emitted ray; the weight is L_e * cos / (pdf_position * pdf_direction).
    virtual std::pair<Ray, Color3f> sample_ray(const Vec2f& u_position, const Vec2f& u_direction) const = 0;
    // Delta-position emitters (point, spot, projector): the solid-angle density with which sample_ray() emits
    // the world direction d (bidirectional MIS needs it for directions it did not sample). 0 for the others.
    virtual float pdf_emission_direction(const Vec3f&) const { return 0.f; }

#define PENUMBRA_EMITTER_METHODS(T)                                                                          \
    /* Solid-angle density of sample_direction() having produced `ds` from `ref` (0 for delta emitters). */  \
    virtual T pdf_direction(const Interaction<T>& ref, const DirectionSample<T>& ds) const = 0;              \
    /* Radiance leaving a surface emitter at si toward si.wi (local); zero on the back side. */              \
    virtual Color3<T> eval(const SurfaceInteraction<T>& si) const = 0;                                       \
    /* Radiance arriving from an infinite emitter along a ray whose world direction is d (escaped rays). */  \
    virtual Color3<T> eval_environment(const Vec3<T>& d) const = 0;                                         \
    /* Delta emitters: the incident term at point p (point/spot: I(ω)/|p - x_src|², directional: E). */      \
    virtual Color3<T> eval_delta(const Vec3<T>& p) const = 0;
    PENUMBRA_FOR_EACH_SCALAR(PENUMBRA_EMITTER_METHODS)
#undef PENUMBRA_EMITTER_METHODS

    // Area lights are attached to their shape; infinite lights learn the scene bounds.
    virtual void set_shape(const Shape* shape) { shape_ = shape; }
    virtual void set_scene_bounds(const BoundingSphere& bounds) { scene_bounds_ = bounds; }
    const Shape* shape() const { return shape_; }
    // Whether the light this emitter casts on `mesh` can jump across the surface (a projector's frustum
    // border, texel edges of a nearest-filtered projected texture, a spot without a falloff ring): a motion
    // of the mesh moves such a jump in its material frame, a boundary the estimators do not sample.
    virtual bool emission_jumps_on(const TriangleMesh&) const { return false; }
    // The placement of point, spot, projector, directional and envmap lights (their emitter-to-world
    // transform, light at the origin, emitting along local +z), which the emitter motions of
    // diff/parameters.h move.
    virtual bool movable() const { return false; }
    virtual Transform to_world() const { return {}; }
    virtual void set_to_world(const Transform&) {}
    // Total emitted power estimate (used to report; emitters are selected uniformly as in Mitsuba 3).
    virtual Color3f power() const { return Color3f(0.f); }
    // The medium the emitter sits in (Mitsuba's nested `medium`), or null if not declared
    // (render/light_medium.h then infers it).
    std::shared_ptr<Medium> medium;

protected:
    uint32_t flags_ = 0;
    const Shape* shape_ = nullptr;
    BoundingSphere scene_bounds_;
};

// CRTP helper: an emitter implements `pdf_direction_t`, `eval_t` and `eval_environment_t` as templates, and
// delta emitters `eval_delta_t`.
template <typename Derived> class EmitterBase : public Emitter {
public:
#define PENUMBRA_EMITTER_IMPL(T)                                                                             \
    T pdf_direction(const Interaction<T>& ref, const DirectionSample<T>& ds) const override {                \
        return static_cast<const Derived*>(this)->template pdf_direction_t<T>(ref, ds);                      \
    }                                                                                                        \
    Color3<T> eval(const SurfaceInteraction<T>& si) const override {                                        \
        return static_cast<const Derived*>(this)->template eval_t<T>(si);                                    \
    }                                                                                                        \
    Color3<T> eval_environment(const Vec3<T>& d) const override {                                           \
        return static_cast<const Derived*>(this)->template eval_environment_t<T>(d);                         \
    }                                                                                                        \
    Color3<T> eval_delta(const Vec3<T>& p) const override {                                                 \
        if constexpr (requires(const Derived& e) { e.template eval_delta_t<T>(p); })                         \
            return static_cast<const Derived*>(this)->template eval_delta_t<T>(p);                           \
        else                                                                                                 \
            return Color3<T>(T(0));                                                                          \
    }
    PENUMBRA_FOR_EACH_SCALAR(PENUMBRA_EMITTER_IMPL)
#undef PENUMBRA_EMITTER_IMPL
};

} // namespace penumbra
