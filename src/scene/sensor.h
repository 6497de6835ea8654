// Sensors: perspective (pinhole), thinlens and orthographic cameras, radiance and irradiance meters;
// Mitsuba's conventions (camera looks along local +z, local +x is left, film origin at the top-left corner of
// the image, which is the film's crop window).
#pragma once
#include "core/scalar.h"
#include "core/transform.h"
#include "scene/film.h"
#include "scene/interaction.h"
#include "scene/sampler.h"

#include <memory>

namespace penumbra {

class Medium;
class Shape;

class Sensor : public Object {
public:
    ObjectKind kind() const override { return ObjectKind::Sensor; }
    Transform to_world;
    std::shared_ptr<Film> film;
    std::shared_ptr<SamplerDesc> sampler;
    std::shared_ptr<Medium> medium; // the medium the sensor sits in (Mitsuba's `medium` child), or null
    float near_clip = 1e-2f, far_clip = 1e4f;

    // Whether every world point has one film position, so that film_position() and to_sensor() are exact (a
    // single center of projection: pinhole, orthographic, thinlens with aperture 0); false for a finite lens
    // aperture (thinlens), a single measured ray (radiancemeter) and a shape's irradiance (irradiancemeter).
    virtual bool projects_points() const { return true; }
    // Attaches the sensor to the shape it is nested in (irradiancemeter); the other sensors cannot be nested.
    virtual void attach_to(const Shape&) {
        throw LoadError(location, plugin + ": only an irradiancemeter can be nested in a shape");
    }

    // Primary ray through continuous film position `film_pos` (pixels, [0,W]x[0,H]) and lens point
    // `aperture_sample` (unused by pinholes); weight is 1 for the projective cameras.
    virtual std::pair<Ray, Color3f> sample_ray(const Vec2f& film_pos, const Vec2f& aperture_sample) const = 0;
    // Light tracing: connect `ref` to the sensor (through the lens point `u` of a thin lens). ds.uv is the
    // film position in pixels, ds.pdf the solid-angle density (1 for a pinhole: a delta position), and the
    // weight is W_e / pdf with the importance W_e normalized so that it integrates to 1 over the image (the
    // crop window). Zero weight if ref projects outside the full frame or beyond the filter radius of the
    // image.
    virtual std::pair<DirectionSample3f, Color3f> sample_direction(const Interaction3f& ref, const Vec2f& u) const = 0;
    // Projection of a world point (through the lens center) to continuous film coordinates (pixels); false if
    // behind or outside.
    virtual bool project(const Vec3f& p, Vec2f& film_pos) const = 0;
    // Moves the sensor (recomputes everything derived from to_world).
    virtual void set_transform(const Transform& to_world) = 0;

#define PENUMBRA_SENSOR_METHODS(T)                                                                           \
    /* The film position s(p) (pixels, no bounds check) of world point p and the Jacobian |ds/dA| (pixel */   \
    /* area per unit area) of a surface element at p with normal n; false if p is behind the sensor. */      \
    virtual bool film_position(const Vec3<T>& p, const Vec3<T>& n, Vec2<T>& film_pos, T& jacobian) const = 0; \
    /* Unit world direction from p toward the sensor (the direction of the last path segment). */           \
    virtual Vec3<T> to_sensor(const Vec3<T>& p) const = 0;
    PENUMBRA_FOR_EACH_SCALAR(PENUMBRA_SENSOR_METHODS)
#undef PENUMBRA_SENSOR_METHODS
};

// CRTP helper: a sensor implements `film_position_t` and `to_sensor_t` as templates.
template <typename Derived, typename Base = Sensor> class SensorBase : public Base {
public:
#define PENUMBRA_SENSOR_IMPL(T)                                                                              \
    bool film_position(const Vec3<T>& p, const Vec3<T>& n, Vec2<T>& film_pos, T& jacobian) const override {  \
        return static_cast<const Derived*>(this)->template film_position_t<T>(p, n, film_pos, jacobian);    \
    }                                                                                                        \
    Vec3<T> to_sensor(const Vec3<T>& p) const override {                                                     \
        return static_cast<const Derived*>(this)->template to_sensor_t<T>(p);                                \
    }
    PENUMBRA_FOR_EACH_SCALAR(PENUMBRA_SENSOR_IMPL)
#undef PENUMBRA_SENSOR_IMPL
};

} // namespace penumbra
