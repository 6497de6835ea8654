// Mitsuba 3 `radiancemeter`: the radiance arriving at one point from one direction (a single ray).
//
// Parameters (plus the common sensor parameters, see sensors/factory.cpp):
//   origin     point    --   where the radiance is measured       } both or neither; ignored when to_world is
//   direction  vector   --   the direction the sensor looks along } given (Mitsuba gives to_world priority)
//   to_world   transform     the ray starts at its origin and travels along its local +z
// The film must be 1 pixel wide or high (Mitsuba refuses a film with neither side 1); every pixel measures
// the same ray, with weight 1, whatever the film and lens samples. Light tracing never reaches the sensor (a
// delta position and direction): sample_direction returns zero, so a `ptracer` image is black, as in Mitsuba.
#include "core/frame.h"
#include "scene/sensors/sensor_common.h"

namespace penumbra {

namespace {

class RadianceMeter final : public SensorBase<RadianceMeter, MeterSensor> {
  public:
    void set_transform(const Transform& t) override {
        to_world = t;
        origin_ = to_world.apply_point(Vec3f(0.f));
        direction_ = normalize(to_world.apply_vector(Vec3f(0.f, 0.f, 1.f)));
    }

    std::pair<Ray, Color3f> sample_ray(const Vec2f&, const Vec2f&) const override {
        return {Ray(origin_, direction_), Color3f(1.f)};
    }

    template <typename T> Vec3<T> to_sensor_t(const Vec3<T>&) const { return Vec3<T>(-direction_); }

    std::string to_string() const override { return "RadianceMeter[film=" + film->to_string() + "]"; }

  private:
    Vec3f origin_, direction_{0.f, 0.f, 1.f};
};

} // namespace

std::shared_ptr<Sensor> make_radiancemeter_sensor(const Properties& props, const LoadContext& ctx) {
    auto meter = std::make_shared<RadianceMeter>();
    load_sensor_common(*meter, props, ctx);
    const bool has_origin = props.has("origin"), has_direction = props.has("direction");
    Transform to_world = meter->to_world;
    if (props.has("to_world")) {
        if (has_origin) props.get_vector("origin");
        if (has_direction) props.get_vector("direction");
    } else if (has_origin != has_direction) {
        props.raise(has_origin ? "origin" : "direction",
                    "origin and direction must be given together (or neither, with to_world)");
    } else if (has_origin) {
        const Vec3f origin = props.get_vector("origin"), direction = props.get_vector("direction");
        if (!(norm(direction) > 0.f)) props.raise("direction", "direction must not be zero");
        Vec3f up, unused;
        coordinate_system(normalize(direction), up, unused);
        to_world = Transform::look_at(origin, origin + direction, up);
    }
    const Film& film = *meter->film;
    if (film.full_size.x != 1 && film.full_size.y != 1)
        throw LoadError(film.location, "radiancemeter: the film must be 1 pixel wide or high (got " +
                                           std::to_string(film.full_size.x) + "x" +
                                           std::to_string(film.full_size.y) + ")");
    meter->set_transform(to_world);
    return meter;
}

} // namespace penumbra
