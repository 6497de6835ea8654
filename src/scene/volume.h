// Volumes: spatially varying quantities of participating media (Mitsuba 3's Volume plugins: `constvolume`,
// `gridvolume`), evaluated at world-space points. A medium's sigma_t and albedo are volumes.
#pragma once
#include "core/param.h"
#include "core/scalar.h"
#include "core/transform.h"
#include "scene/object.h"

#include <functional>

namespace penumbra {

// An axis-aligned box in world space (empty when lo > hi).
struct BoundingBox3f {
    Vec3f lo{Infinity, Infinity, Infinity}, hi{-Infinity, -Infinity, -Infinity};
    bool is_valid() const { return lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z; }
    // The parameter interval [t0, t1] of `o + t d` inside the box (false if the ray misses it).
    bool intersect(const Vec3f& o, const Vec3f& d, float& t0, float& t1) const;
};

class Volume : public Object {
  public:
    ObjectKind kind() const override { return ObjectKind::Volume; }
#define PENUMBRA_VOLUME_METHODS(T)                                                                           \
    /* The value at world point p (RGB; single-channel grids repeat their value in the three channels). */   \
    virtual Color3<T> eval(const Vec3<T>& p) const = 0;
    PENUMBRA_FOR_EACH_SCALAR(PENUMBRA_VOLUME_METHODS)
#undef PENUMBRA_VOLUME_METHODS
    // The largest channel value anywhere (a majorant of every channel).
    virtual float max() const = 0;
    // The smallest channel value anywhere (loaders reject grids that would give a negative extinction).
    virtual float min() const = 0;
    // A bound of every channel's value over the world-space segment o + t d, t in [t0, t1] (grids refine it
    // with a coarse grid of maxima; the default is max()).
    virtual float max_along(const Vec3f& o, const Vec3f& d, float t0, float t1) const {
        (void)o, (void)d, (void)t0, (void)t1;
        return max();
    }
    // Piecewise-constant bounds along o + t d over [t0, t1): calls f(s0, s1, bound) for consecutive segments
    // covering the interval, in order, with bound >= every channel's value on [s0, s1); stops when f returns
    // false. Grids report one segment per block of their coarse grid of maxima; the default is one segment.
    using BoundVisitor = std::function<bool(float s0, float s1, float bound)>;
    virtual void max_segments(const Vec3f& o, const Vec3f& d, float t0, float t1,
                              const BoundVisitor& f) const {
        if (t0 < t1) f(t0, t1, max_along(o, d, t0, t1));
    }
    // World-space support outside which the value is that of the nearest boundary texel (grids) or the
    // constant (constvolume: an invalid box, meaning everywhere).
    virtual BoundingBox3f bbox() const { return {}; }
    virtual bool is_constant() const { return false; }
    // Number of channels stored (1 or 3).
    virtual int channel_count() const { return 3; }
};

// CRTP helper: a volume implements `template <typename T> Color3<T> eval_t(const Vec3<T>& p) const`.
template <typename Derived> class VolumeBase : public Volume {
  public:
#define PENUMBRA_VOLUME_IMPL(T)                                                                              \
    Color3<T> eval(const Vec3<T>& p) const override {                                                        \
        return static_cast<const Derived*>(this)->template eval_t<T>(p);                                     \
    }
    PENUMBRA_FOR_EACH_SCALAR(PENUMBRA_VOLUME_IMPL)
#undef PENUMBRA_VOLUME_IMPL
};

// `constvolume`: one value everywhere.
class ConstVolume : public VolumeBase<ConstVolume> {
  public:
    explicit ConstVolume(const Color3f& value) : value(value) {}
    template <typename T> Color3<T> eval_t(const Vec3<T>&) const {
        return param_color<T>(value, param_index);
    }
    float max() const override { return max_component(value); }
    float min() const override { return min_component(value); }
    bool is_constant() const override { return true; }
    void traverse(ParamVisitor& v) override { v.put("value", &value.x, 3, &param_index); }
    Color3f value;
    int param_index = -1; // first parameter index when `value` is differentiated
};

} // namespace penumbra
