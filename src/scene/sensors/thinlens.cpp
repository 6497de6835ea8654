// Mitsuba 3 `thinlens` camera: the perspective camera with a thin lens at a circular aperture (depth of
// field).
//
// Parameters (plus the common sensor parameters, see sensors/factory.cpp):
//   aperture_radius           float  --        lens aperture radius in scene units (required; >= 0)
//   focus_distance            float  far_clip  distance from the lens to the plane in focus, along local +z
//   fov, fov_axis, focal_length              as for `perspective` (sensors/fov.cpp)
//   principal_point_offset_x  float  0         as for `perspective` (a penumbra extension: Mitsuba's
//   principal_point_offset_y  float  0         thinlens has no principal point offset)
//
// A primary ray (Mitsuba's ThinLensCamera::sample_ray): the aperture point a = r · concentric_disk(u) on the
// lens plane z = 0 and the point f = focus_distance · q(s) of the plane in focus that the film position s
// images (q(s) on z = 1, see PerspectiveProjection), d = normalize(f − a); the ray starts at the near clip
// plane and its weight is 1. Points on the plane in focus therefore image exactly as with a pinhole; a point
// at depth z spreads over a uniform disk (circle of confusion) of radius r |z − F| / (z F) on the plane
// z = 1, F = focus_distance.
#include "scene/sensors/sensor_common.h"

#include "core/warp.h"

#include <cmath>

namespace penumbra {

namespace {

class ThinLensCamera final : public SensorBase<ThinLensCamera, PerspectiveProjection> {
  public:
    // Called once the film and the transform are set.
    void configure(float x_fov_deg, const Vec2f& principal_point_offset, float aperture_radius,
                   float focus_distance) {
        configure_perspective(x_fov_deg, principal_point_offset);
        aperture_radius_ = aperture_radius;
        focus_distance_ = focus_distance;
    }

    bool projects_points() const override { return aperture_radius_ == 0.f; }

    std::pair<Ray, Color3f> sample_ray(const Vec2f& film_pos, const Vec2f& aperture_sample) const override {
        const Vec2f disk = warp::square_to_uniform_disk_concentric(aperture_sample) * aperture_radius_;
        const Vec3f a(disk.x, disk.y, 0.f);
        const Vec3f d = normalize(plane_point(film_pos) * focus_distance_ - a);
        const float near_t = near_clip / d.z, far_t = far_clip / d.z;
        const Vec3f dir = normalize(to_world.apply_vector(d));
        return {Ray(to_world.apply_point(a) + dir * near_t, dir, far_t - near_t), Color3f(1.f)};
    }

    // Mitsuba's ThinLensCamera::sample_direction: a uniform aperture point a (area density 1 / (π r²)), the
    // film position imaged by the direction a → ref, and the weight W(d) / dist² with the pinhole importance
    // W (the lens importance W / (π r² cos θ) per unit lens area and solid angle, times the geometry term cos
    // θ / dist², over the aperture density). ds.pdf is the solid-angle density of a seen from ref: dist² / (π
    // r² cos θ).
    std::pair<DirectionSample3f, Color3f> sample_direction(const Interaction3f& ref,
                                                           const Vec2f& u) const override {
        DirectionSample3f ds;
        const Vec3f q = to_local_.apply_point(ref.p);
        if (!(q.z >= near_clip && q.z <= far_clip)) return {ds, Color3f(0.f)};
        const Vec2f disk = warp::square_to_uniform_disk_concentric(u) * aperture_radius_;
        const Vec3f a(disk.x, disk.y, 0.f);
        const Vec3f to_ref = q - a;
        const float dist = norm(to_ref);
        const float cos_theta = to_ref.z / dist;
        // Where the direction meets the plane in focus, and the film position imaging that point.
        const Vec3f f = a + to_ref * (focus_distance_ / to_ref.z);
        const Vec2f film_pos = film_position_of(f.x / f.z, f.y / f.z);
        if (!reaches_image(film_pos)) return {ds, Color3f(0.f)};
        ds.p = to_world.apply_point(a);
        ds.n = forward_;
        ds.uv = film_pos;
        ds.d = (ds.p - ref.p) / dist;
        ds.dist = dist;
        ds.delta = aperture_radius_ == 0.f;
        ds.pdf = ds.delta ? 1.f : dist * dist / (Pi * aperture_radius_ * aperture_radius_ * cos_theta);
        return {ds, Color3f(importance(cos_theta) / (dist * dist))};
    }

    void set_transform(const Transform& t) override {
        to_world = t;
        configure(x_fov_, ppo_, aperture_radius_, focus_distance_);
    }

    std::string to_string() const override {
        return "ThinLensCamera[x_fov=" + std::to_string(x_fov_) +
               ", aperture_radius=" + std::to_string(aperture_radius_) +
               ", focus_distance=" + std::to_string(focus_distance_) + ", film=" + film->to_string() + "]";
    }

  private:
    float aperture_radius_ = 0.f, focus_distance_ = 1.f;
};

} // namespace

std::shared_ptr<Sensor> make_thinlens_sensor(const Properties& props, const LoadContext& ctx) {
    auto camera = std::make_shared<ThinLensCamera>();
    load_sensor_common(*camera, props, ctx);
    const PerspectiveParameters pp = load_perspective_parameters(props, *camera);
    const float radius = props.get_float("aperture_radius");
    if (!(radius >= 0.f)) props.raise("aperture_radius", "aperture_radius must not be negative");
    const float focus = props.get_float("focus_distance", camera->far_clip);
    if (!(focus > 0.f)) props.raise("focus_distance", "focus_distance must be positive");
    camera->configure(pp.x_fov, pp.principal_point_offset, radius, focus);
    return camera;
}

} // namespace penumbra
