// Mitsuba 3 `perspective` (pinhole) camera.
//
// Parameters (plus the common sensor parameters, see sensors/factory.cpp):
//   fov                       float   --      field of view in degrees along fov_axis, in (0, 180)
//   fov_axis                  string  x       x | y | diagonal | smaller | larger (only with fov)
//   focal_length              string  50mm    35mm-film-equivalent focal length (when fov is absent)
//   principal_point_offset_x  float   0       principal point shift, in units of the film width
//   principal_point_offset_y  float   0       principal point shift, in units of the film height
//
// Camera space: looks along +z, +x is left, +y up (Transform::look_at). A film position maps to the direction
// d_local ~ q(s) of sensor_common.h (PerspectiveProjection): with s = (px / W, py / H) +
// principal_point_offset, a positive offset moves the image content toward the top-left (Mitsuba's
// perspective_projection()).
#include "scene/sensors/sensor_common.h"

#include <cmath>

namespace penumbra {

namespace {

class PerspectiveCamera final : public SensorBase<PerspectiveCamera, PerspectiveProjection> {
  public:
    // Called once the film and the transform are set.
    void configure(float x_fov_deg, const Vec2f& principal_point_offset) {
        configure_perspective(x_fov_deg, principal_point_offset);
    }

    std::pair<Ray, Color3f> sample_ray(const Vec2f& film_pos, const Vec2f&) const override {
        const Vec3f local = normalize(plane_point(film_pos));
        return {Ray(origin_, normalize(to_world.apply_vector(local)), far_clip / local.z), Color3f(1.f)};
    }

    // Delta position: weight = W(d) / dist^2 with the importance of PerspectiveProjection.
    std::pair<DirectionSample3f, Color3f> sample_direction(const Interaction3f& ref,
                                                           const Vec2f&) const override {
        DirectionSample3f ds;
        const Vec3f q = to_local_.apply_point(ref.p);
        if (!(q.z >= near_clip && q.z <= far_clip)) return {ds, Color3f(0.f)};
        const Vec2f film_pos = film_position_of(q.x / q.z, q.y / q.z);
        if (!reaches_image(film_pos)) return {ds, Color3f(0.f)};
        const Vec3f to_camera = origin_ - ref.p;
        const float dist = norm(to_camera);
        const float cos_theta = q.z / dist;
        ds.p = origin_;
        ds.n = forward_;
        ds.uv = film_pos;
        ds.d = to_camera / dist;
        ds.dist = dist;
        ds.pdf = 1.f;
        ds.delta = true;
        return {ds, Color3f(importance(cos_theta) / (dist * dist))};
    }

    void set_transform(const Transform& t) override {
        to_world = t;
        configure(x_fov_, ppo_);
    }

    std::string to_string() const override {
        return "PerspectiveCamera[x_fov=" + std::to_string(x_fov_) + ", film=" + film->to_string() + "]";
    }
};

} // namespace

std::shared_ptr<Sensor> make_perspective_sensor(const Properties& props, const LoadContext& ctx) {
    auto camera = std::make_shared<PerspectiveCamera>();
    load_sensor_common(*camera, props, ctx);
    const PerspectiveParameters pp = load_perspective_parameters(props, *camera);
    camera->configure(pp.x_fov, pp.principal_point_offset);
    return camera;
}

} // namespace penumbra
