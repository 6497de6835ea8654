// What the sensor plugins of this directory share: the common parameters (Mitsuba's Sensor) and the film
// geometry of projective cameras (Mitsuba's ProjectiveCamera).
#pragma once
#include "scene/factory.h"
#include "scene/sensor.h"

namespace penumbra {

// Parses the parameters shared by all sensors into `sensor` (to_world, clip planes, shutter, nested film and
// sampler with their defaults); see sensors/factory.cpp for the table.
void load_sensor_common(Sensor& sensor, const Properties& props, const LoadContext& ctx);

// Mitsuba's parse_fov(): the horizontal field of view in degrees from fov / fov_axis / focal_length for an
// image of the given aspect (W / H); also used by the projector emitter.
float parse_x_fov(const Properties& props, double aspect);

// The sensor plugins, one per file of this directory; make_sensor (factory.cpp) dispatches on `type`.
std::shared_ptr<Sensor> make_perspective_sensor(const Properties& props, const LoadContext& ctx);
std::shared_ptr<Sensor> make_orthographic_sensor(const Properties& props, const LoadContext& ctx);

// A camera that maps film positions (pixels, (0, 0) = top-left) to rays along to_world's +z.
class ProjectiveCamera : public Sensor {
  protected:
    // Called once the film and the transform are set.
    void configure_projection() {
        size_ = Vec2f(float(film->width), float(film->height));
        aspect_ = size_.x / size_.y;
        to_local_ = to_world.inverse();
        forward_ = normalize(to_world.apply_vector(Vec3f(0.f, 0.f, 1.f)));
    }

    // Whether a film position (pixels) lies on the film, edges included.
    bool on_film(const Vec2f& film_pos) const {
        return film_pos.x >= 0.f && film_pos.x <= size_.x && film_pos.y >= 0.f && film_pos.y <= size_.y;
    }

    Vec2f size_;         // film size in pixels
    float aspect_ = 1.f; // width / height
    Transform to_local_; // inverse of to_world
    Vec3f forward_;      // world-space view direction
};

} // namespace penumbra
