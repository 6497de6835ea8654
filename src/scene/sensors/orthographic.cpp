// Mitsuba 3 `orthographic` camera. No parameters of its own (see sensors/factory.cpp for the common ones).
//
// The film covers the camera-space rectangle x in [-1, 1], y in [-1/aspect, 1/aspect] (aspect = W / H) on the
// near plane z = near_clip, scaled and placed by to_world (its scale sets the view extent). Film position
// (px, py) in pixels, (0, 0) = top-left, maps to the camera-space point (1 - 2 fx / W, (1 - 2 fy / H) /
// aspect), with (fx, fy) = (px, py) + crop_offset the position in the full frame; rays travel along
// to_world's +z.
#include "scene/sensors/sensor_common.h"

#include <cmath>

namespace penumbra {

namespace {

class OrthographicCamera final : public SensorBase<OrthographicCamera, ProjectiveCamera> {
  public:
    // Called once the film and the transform are set.
    void configure() {
        configure_projection();
        // World-space area of the film rectangle: |X x Y| * 2 * (2 / aspect).
        const Vec3f x_axis = to_world.apply_vector(Vec3f(1.f, 0.f, 0.f));
        const Vec3f y_axis = to_world.apply_vector(Vec3f(0.f, 1.f, 0.f));
        film_area_ = norm(cross(x_axis, y_axis)) * 4.f / aspect_;
    }

    std::pair<Ray, Color3f> sample_ray(const Vec2f& film_pos, const Vec2f&) const override {
        const Vec2f f = film_pos + crop_offset_;
        const Vec3f local(1.f - 2.f * f.x / size_.x, (1.f - 2.f * f.y / size_.y) / aspect_, near_clip);
        return {Ray(to_world.apply_point(local), forward_, far_clip - near_clip), Color3f(1.f)};
    }

    bool project(const Vec3f& p, Vec2f& film_pos) const override {
        const Vec3f q = to_local_.apply_point(p);
        if (!(q.z >= near_clip && q.z <= far_clip)) return false;
        film_pos = film_position_of(q);
        return on_film(film_pos);
    }

    // Delta direction: the connection is the point of the film that sees `ref` along the view direction.
    // Importance W = 1 / A_film (integrates to 1 over the film's world-space area, scaled to the crop
    // window); pdf 1, weight = W.
    std::pair<DirectionSample3f, Color3f> sample_direction(const Interaction3f& ref,
                                                           const Vec2f&) const override {
        DirectionSample3f ds;
        const Vec3f q = to_local_.apply_point(ref.p);
        if (!(q.z >= near_clip && q.z <= far_clip)) return {ds, Color3f(0.f)};
        const Vec2f film_pos = film_position_of(q);
        if (!reaches_image(film_pos)) return {ds, Color3f(0.f)};
        ds.p = to_world.apply_point(Vec3f(q.x, q.y, near_clip));
        ds.n = forward_;
        ds.uv = film_pos;
        const Vec3f to_camera = ds.p - ref.p;
        ds.dist = norm(to_camera);
        ds.d = ds.dist > 0.f ? to_camera / ds.dist : -forward_;
        ds.pdf = 1.f;
        ds.delta = true;
        return {ds, Color3f(crop_importance_scale() / film_area_)};
    }

    void set_transform(const Transform& t) override {
        to_world = t;
        configure();
    }

    // s(p) as in project(), and |ds/dA| = (W H / A_film) |cos θ_p| (parallel projection).
    template <typename T> bool film_position_t(const Vec3<T>& p, const Vec3<T>& n, Vec2<T>& film_pos, T& jacobian) const {
        using std::abs;
        const Vec3<T> q = to_local_.apply_point(p);
        if (!(detach(q.z) >= near_clip)) return false;
        film_pos = film_position_of(q);
        jacobian = T(size_.x * size_.y / film_area_) * abs(dot(n, Vec3<T>(forward_)));
        return true;
    }
    template <typename T> Vec3<T> to_sensor_t(const Vec3<T>&) const { return Vec3<T>(-forward_); }

    std::string to_string() const override { return "OrthographicCamera[film=" + film->to_string() + "]"; }

  private:
    // The film position (pixels) of a camera-space point.
    template <typename T> Vec2<T> film_position_of(const Vec3<T>& q) const {
        return Vec2<T>(T(0.5f) * (T(1.f) - q.x) * T(size_.x) - T(crop_offset_.x),
                       T(0.5f) * (T(1.f) - T(aspect_) * q.y) * T(size_.y) - T(crop_offset_.y));
    }

    float film_area_ = 1.f;
};

} // namespace

std::shared_ptr<Sensor> make_orthographic_sensor(const Properties& props, const LoadContext& ctx) {
    auto camera = std::make_shared<OrthographicCamera>();
    load_sensor_common(*camera, props, ctx);
    camera->configure();
    return camera;
}

} // namespace penumbra
