// Mitsuba 3 `irradiancemeter`: the irradiance arriving at a shape, averaged over its surface. It is nested in
// the shape it measures (<shape ...><sensor type="irradiancemeter"/></shape>) and has no parameters of its
// own (the common ones are accepted, see sensors/factory.cpp); its film has a single pixel.
//
// Mitsuba's IrradianceMeter::sample_ray: a point x uniform on the shape (the lens sample) and a
// cosine-weighted direction ω about its normal (the film sample), weight π, so that the pixel reads
//   E = (1 / A) ∫_A ∫_H² L(x, ω) cos θ dω dA
// (π L under a constant environment of radiance L). The direction sample is the film position within the one
// pixel, which is uniform only for a box filter: the meter's film always uses one (a 1-pixel film of a
// measurement that varies inside the pixel has no other sensible filter; Mitsuba warns for wider filters,
// whose weights would bias the average).
#include "core/frame.h"
#include "core/warp.h"
#include "scene/sensors/sensor_common.h"
#include "scene/shape.h"

#include <algorithm>

namespace penumbra {

namespace {

class IrradianceMeter final : public SensorBase<IrradianceMeter, MeterSensor> {
  public:
    void attach_to(const Shape& shape) override { shape_ = &shape; }
    void set_transform(const Transform& t) override { to_world = t; }

    std::pair<Ray, Color3f> sample_ray(const Vec2f& film_pos, const Vec2f& aperture_sample) const override {
        if (!shape_) return {Ray(Vec3f(0.f), Vec3f(0.f, 0.f, 1.f), 0.f), Color3f(0.f)};
        const PositionSample3f ps = shape_->sample_position(aperture_sample);
        Interaction3f at;
        at.p = ps.p;
        at.n = ps.n;
        const Vec2f u(std::clamp(film_pos.x, 0.f, 1.f), std::clamp(film_pos.y, 0.f, 1.f));
        const Vec3f d = Frame3f(ps.n).to_world(warp::square_to_cosine_hemisphere(u));
        // cos θ / p(ω) = π, and 1 / (A p(x)) = 1 for the uniform area density.
        return {at.spawn_ray(d), Color3f(Pi / (shape_->surface_area() * ps.pdf))};
    }

    template <typename T> Vec3<T> to_sensor_t(const Vec3<T>&) const { return Vec3<T>(0.f, 0.f, 1.f); }

    std::string to_string() const override { return "IrradianceMeter[film=" + film->to_string() + "]"; }

  private:
    const Shape* shape_ = nullptr;
};

} // namespace

std::shared_ptr<Sensor> make_irradiancemeter_sensor(const Properties& props, const LoadContext& ctx) {
    auto meter = std::make_shared<IrradianceMeter>();
    load_sensor_common(*meter, props, ctx);
    Film& film = *meter->film;
    if (!(film.full_size == Vec2i(1, 1)))
        throw LoadError(film.location, "irradiancemeter: the film must have 1x1 pixels (got " +
                                           std::to_string(film.full_size.x) + "x" +
                                           std::to_string(film.full_size.y) + ")");
    if (film.rfilter->plugin != "box") {
        film.rfilter = std::static_pointer_cast<ReconstructionFilter>(
            make_rfilter(Properties("box", film.location), ctx));
        film.rfilter->plugin = "box";
        film.rfilter->location = film.location;
    }
    return meter;
}

} // namespace penumbra
