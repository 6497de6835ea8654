// Mitsuba 3 `orthographic` camera. No parameters of its own (see sensors/factory.cpp for the common ones).
//
// The film covers the camera-space rectangle x in [-1, 1], y in [-1/aspect, 1/aspect] (aspect = W / H) on the
// near plane z = near_clip, scaled and placed by to_world (its scale sets the view extent). Film position
// (px, py) in pixels, (0, 0) = top-left, maps to the camera-space point (1 - 2 px / W, (1 - 2 py / H) /
// aspect); rays travel along to_world's +z.
#include "scene/factory.h"
#include "scene/sensor.h"

#include <cmath>

namespace penumbra {

void load_sensor_common(Sensor& sensor, const Properties& props,
                        const LoadContext& ctx); // sensors/factory.cpp

namespace {

class OrthographicCamera final : public Sensor {
  public:
    // Called once the film and the transform are set.
    void configure() {
        size_ = Vec2f(float(film->width), float(film->height));
        aspect_ = size_.x / size_.y;
        to_local_ = to_world.inverse();
        forward_ = normalize(to_world.apply_vector(Vec3f(0.f, 0.f, 1.f)));
        // World-space area of the film rectangle: |X x Y| * 2 * (2 / aspect).
        const Vec3f x_axis = to_world.apply_vector(Vec3f(1.f, 0.f, 0.f));
        const Vec3f y_axis = to_world.apply_vector(Vec3f(0.f, 1.f, 0.f));
        film_area_ = norm(cross(x_axis, y_axis)) * 4.f / aspect_;
    }

    std::pair<Ray, Color3f> sample_ray(const Vec2f& film_pos, const Vec2f&) const override {
        const Vec3f local(1.f - 2.f * film_pos.x / size_.x, (1.f - 2.f * film_pos.y / size_.y) / aspect_,
                          near_clip);
        return {Ray(to_world.apply_point(local), forward_, far_clip - near_clip), Color3f(1.f)};
    }

    bool project(const Vec3f& p, Vec2f& film_pos) const override {
        const Vec3f q = to_local_.apply_point(p);
        if (!(q.z >= near_clip && q.z <= far_clip)) return false;
        film_pos = Vec2f(0.5f * (1.f - q.x) * size_.x, 0.5f * (1.f - aspect_ * q.y) * size_.y);
        return film_pos.x >= 0.f && film_pos.x <= size_.x && film_pos.y >= 0.f && film_pos.y <= size_.y;
    }

    // Delta direction: the connection is the point of the film that sees `ref` along the view direction.
    // Importance W = 1 / A_film (integrates to 1 over the film's world-space area); pdf 1, weight = W.
    std::pair<DirectionSample3f, Color3f> sample_direction(const Interaction3f& ref,
                                                           const Vec2f&) const override {
        DirectionSample3f ds;
        Vec2f film_pos;
        if (!project(ref.p, film_pos)) return {ds, Color3f(0.f)};
        const Vec3f q = to_local_.apply_point(ref.p);
        ds.p = to_world.apply_point(Vec3f(q.x, q.y, near_clip));
        ds.n = forward_;
        ds.uv = film_pos;
        const Vec3f to_camera = ds.p - ref.p;
        ds.dist = norm(to_camera);
        ds.d = ds.dist > 0.f ? to_camera / ds.dist : -forward_;
        ds.pdf = 1.f;
        ds.delta = true;
        return {ds, Color3f(1.f / film_area_)};
    }

    std::string to_string() const override { return "OrthographicCamera[film=" + film->to_string() + "]"; }

  private:
    Vec2f size_;
    float aspect_ = 1.f, film_area_ = 1.f;
    Transform to_local_;
    Vec3f forward_;
};

} // namespace

std::shared_ptr<Sensor> make_orthographic_sensor(const Properties& props, const LoadContext& ctx) {
    auto camera = std::make_shared<OrthographicCamera>();
    load_sensor_common(*camera, props, ctx);
    camera->configure();
    return camera;
}

} // namespace penumbra
