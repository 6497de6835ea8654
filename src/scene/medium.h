// Participating media (Mitsuba 3's `homogeneous` and `heterogeneous`): an extinction sigma_t and a
// single-scattering albedo, both volumes (RGB, per channel), and a phase function. Media are attached to
// shapes (`interior`, `exterior`) and to the sensor; integrators track the medium a ray travels in
// (target_medium below) and sample it with the free-flight and transmittance estimators of
// render/medium_sampling.h, which only see the interface here.
#pragma once
#include "scene/phase.h"
#include "scene/volume.h"

#include <functional>
#include <memory>

namespace penumbra {

class Medium : public Object {
  public:
    ObjectKind kind() const override { return ObjectKind::Medium; }
    std::shared_ptr<PhaseFunction> phase;
    // Mitsuba's `sample_emitters`: next-event estimation inside the medium (off: emitters are found by
    // phase-function sampling only). Changes the variance, not the expectation.
    bool sample_emitters = true;

    // sigma_t is constant in space (closed-form free-flight sampling and transmittance).
    virtual bool is_homogeneous() const = 0;
#define PENUMBRA_MEDIUM_METHODS(T)                                                                           \
    /* Extinction sigma_t (1/length, `scale` applied) and albedo sigma_s/sigma_t at world point p. */        \
    virtual Color3<T> sigma_t(const Vec3<T>& p) const = 0;                                                   \
    virtual Color3<T> albedo(const Vec3<T>& p) const = 0;
    PENUMBRA_FOR_EACH_SCALAR(PENUMBRA_MEDIUM_METHODS)
#undef PENUMBRA_MEDIUM_METHODS
    // Piecewise-constant grey majorants along o + t d (d unit) over [tmin, tmax): calls f(t0, t1, majorant)
    // for consecutive segments covering the interval, in order, with majorant >= every channel of sigma_t
    // on [t0, t1); stops early when f returns false. Homogeneous media report one segment.
    using MajorantVisitor = std::function<bool(float t0, float t1, float majorant)>;
    virtual void majorants(const Vec3f& o, const Vec3f& d, float tmin, float tmax,
                           const MajorantVisitor& f) const = 0;
};

// CRTP helper: a medium implements `sigma_t_t<T>(p)` and `albedo_t<T>(p)`.
template <typename Derived> class MediumBase : public Medium {
  public:
#define PENUMBRA_MEDIUM_IMPL(T)                                                                              \
    Color3<T> sigma_t(const Vec3<T>& p) const override {                                                     \
        return static_cast<const Derived*>(this)->template sigma_t_t<T>(p);                                  \
    }                                                                                                        \
    Color3<T> albedo(const Vec3<T>& p) const override {                                                      \
        return static_cast<const Derived*>(this)->template albedo_t<T>(p);                                   \
    }
    PENUMBRA_FOR_EACH_SCALAR(PENUMBRA_MEDIUM_IMPL)
#undef PENUMBRA_MEDIUM_IMPL
};

// `homogeneous`: constant extinction (a constvolume, times `scale`); the albedo may vary in space.
class HomogeneousMedium : public MediumBase<HomogeneousMedium> {
  public:
    std::shared_ptr<Volume> sigma_t_volume, albedo_volume;
    float scale = 1.f;
    bool is_homogeneous() const override { return true; }
    template <typename T> Color3<T> sigma_t_t(const Vec3<T>& p) const { return sigma_t_volume->eval(p) * T(scale); }
    template <typename T> Color3<T> albedo_t(const Vec3<T>& p) const { return albedo_volume->eval(p); }
    void majorants(const Vec3f&, const Vec3f&, float tmin, float tmax, const MajorantVisitor& f) const override {
        if (tmin < tmax) f(tmin, tmax, sigma_t_volume->max() * scale);
    }
    void traverse(ParamVisitor& v) override;
};

// The medium on the side of a surface that direction d (world) points into: Mitsuba's
// SurfaceInteraction::target_medium — the exterior if d·n > 0 (n the geometric normal), else the interior.
// Surfaces of shapes that declare no medium are not medium transitions: the current medium continues.
template <typename Shape>
inline const Medium* target_medium(const Shape& shape, const Vec3f& n, const Vec3f& d, const Medium* current) {
    if (!shape.interior && !shape.exterior) return current;
    return dot(d, n) > 0.f ? shape.exterior.get() : shape.interior.get();
}

} // namespace penumbra
