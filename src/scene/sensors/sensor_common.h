// What the sensor plugins of this directory share: the common parameters (Mitsuba's Sensor) and the film
// geometry of projective cameras (Mitsuba's ProjectiveCamera).
#pragma once
#include "scene/factory.h"
#include "scene/sensor.h"

#include <cmath>

namespace penumbra {

// Parses the parameters shared by all sensors into `sensor` (to_world, clip planes, shutter, nested film and
// sampler with their defaults); see sensors/factory.cpp for the table.
void load_sensor_common(Sensor& sensor, const Properties& props, const LoadContext& ctx);

// The sensor plugins, one per file of this directory; make_sensor (factory.cpp) dispatches on `type`.
std::shared_ptr<Sensor> make_perspective_sensor(const Properties& props, const LoadContext& ctx);
std::shared_ptr<Sensor> make_orthographic_sensor(const Properties& props, const LoadContext& ctx);
std::shared_ptr<Sensor> make_thinlens_sensor(const Properties& props, const LoadContext& ctx);
std::shared_ptr<Sensor> make_radiancemeter_sensor(const Properties& props, const LoadContext& ctx);
std::shared_ptr<Sensor> make_irradiancemeter_sensor(const Properties& props, const LoadContext& ctx);

// Mitsuba's parse_fov() (fov, fov_axis or focal_length): the horizontal field of view in degrees for an image
// of the given aspect (W / H) (sensors/fov.cpp); also used by the projector emitter.
float parse_x_fov(const Properties& props, double aspect);

// A meter: a sensor onto which no scene point projects (it measures a set of rays of measure zero for light
// tracing), so light tracing cannot connect to it (a ptracer image is black, as in Mitsuba) and the
// estimators that connect points to the camera are refused (diff/first_vertex.h). Meters define sample_ray
// and to_sensor_t.
class MeterSensor : public Sensor {
  public:
    bool projects_points() const override { return false; }
    std::pair<DirectionSample3f, Color3f> sample_direction(const Interaction3f&,
                                                           const Vec2f&) const override {
        return {DirectionSample3f(), Color3f(0.f)};
    }
    bool project(const Vec3f&, Vec2f&) const override { return false; }
    template <typename T> bool film_position_t(const Vec3<T>&, const Vec3<T>&, Vec2<T>&, T&) const {
        return false;
    }
};

// A camera that maps film positions (pixels, (0, 0) = top-left of the image) to rays along to_world's +z. The
// projection covers the film's full frame; the image is its crop window (film.h), so a film position s is the
// frame position s + crop_offset.
class ProjectiveCamera : public Sensor {
  protected:
    // Called once the film and the transform are set.
    void configure_projection() {
        size_ = Vec2f(film->full_size);
        crop_offset_ = Vec2f(film->crop_offset);
        crop_size_ = Vec2f(float(film->width), float(film->height));
        aspect_ = size_.x / size_.y;
        to_local_ = to_world.inverse();
        forward_ = normalize(to_world.apply_vector(Vec3f(0.f, 0.f, 1.f)));
    }

    // Whether a film position (pixels) lies on the image (the crop window), edges included.
    bool on_film(const Vec2f& film_pos) const {
        return film_pos.x >= 0.f && film_pos.x <= crop_size_.x && film_pos.y >= 0.f &&
               film_pos.y <= crop_size_.y;
    }
    // Whether light tracing splats at a film position: within the filter's reach of the image, and on the full
    // frame unless the film samples the border band beyond it (sample_border), so that the image's border
    // pixels get what a camera-driven render gives them.
    bool reaches_image(const Vec2f& film_pos) const {
        const float r = film->rfilter->radius();
        const Vec2f f = film_pos + crop_offset_;
        const bool in_frame = film->sample_border || (f.x >= 0.f && f.x <= size_.x && f.y >= 0.f && f.y <= size_.y);
        return in_frame && film_pos.x >= -r &&
               film_pos.x <= crop_size_.x + r && film_pos.y >= -r && film_pos.y <= crop_size_.y + r;
    }
    // The factor that makes an importance normalized over the full frame integrate to 1 over the image:
    // frame pixels / image pixels (light tracing divides by the image's pixel count).
    float crop_importance_scale() const { return size_.x * size_.y / (crop_size_.x * crop_size_.y); }

    Vec2f size_;         // full frame size in pixels
    Vec2f crop_offset_;  // top-left corner of the image in the frame, pixels
    Vec2f crop_size_;    // image size in pixels
    float aspect_ = 1.f; // width / height of the full frame
    Transform to_local_; // inverse of to_world
    Vec3f forward_;      // world-space view direction
};

// The pinhole projection shared by perspective and thinlens: a film position (px, py) maps to the frame
// fraction s = ((px, py) + crop_offset) / size + principal_point_offset and to the camera-space point
//   q(s) = (tan(fov_x / 2) (1 - 2 s_x), tan(fov_x / 2) (1 - 2 s_y) / aspect, 1)   on the plane z = 1.
class PerspectiveProjection : public ProjectiveCamera {
  public:
    // The projection through the center of projection (a thin lens's chief ray).
    bool project(const Vec3f& p, Vec2f& film_pos) const override {
        const Vec3f q = to_local_.apply_point(p);
        if (!(q.z >= near_clip && q.z <= far_clip)) return false;
        film_pos = film_position_of(q.x / q.z, q.y / q.z);
        return on_film(film_pos);
    }

    // s(p) as in project(), and |ds/dA| = (W H / A) cos θ_p / (d² cos³ θ_c): pixels per unit solid angle
    // (W H / A / cos³ θ_c, A the image-plane area at distance 1) times dω/dA = cos θ_p / d². Exact for a
    // pinhole; for a thin lens it is the lens center's, and the estimators that connect points to the camera
    // refuse a finite aperture (diff/first_vertex.h, require_pinhole).
    template <typename T>
    bool film_position_t(const Vec3<T>& p, const Vec3<T>& n, Vec2<T>& film_pos, T& jacobian) const {
        using std::abs;
        using std::sqrt;
        const Vec3<T> q = to_local_.apply_point(p);
        if (!(detach(q.z) > 0.f)) return false;
        film_pos = film_position_of(q.x / q.z, q.y / q.z);
        const Vec3<T> d = p - Vec3<T>(origin_);
        const T dist2 = squared_norm(d);
        const T dist = sqrt(dist2);
        const T cos_c = q.z / dist;
        const T cos_p = abs(dot(n, d)) / dist;
        jacobian = T(size_.x * size_.y / plane_area_) * cos_p / (dist2 * cos_c * cos_c * cos_c);
        return true;
    }
    template <typename T> Vec3<T> to_sensor_t(const Vec3<T>& p) const {
        return normalize(Vec3<T>(origin_) - p);
    }

  protected:
    void configure_perspective(float x_fov_deg, const Vec2f& principal_point_offset) {
        configure_projection();
        origin_ = to_world.apply_point(Vec3f(0.f));
        x_fov_ = x_fov_deg;
        tan_half_ = std::tan(0.5f * radians(x_fov_deg));
        ppo_ = principal_point_offset;
        // Image-plane area of the full frame at distance 1: (2 tan(fov_x / 2)) x (2 tan(fov_x / 2) / aspect).
        plane_area_ = 4.f * tan_half_ * tan_half_ / aspect_;
    }

    // q(s) on the plane z = 1 for a film position.
    Vec3f plane_point(const Vec2f& film_pos) const {
        const Vec2f s =
            Vec2f((film_pos.x + crop_offset_.x) / size_.x, (film_pos.y + crop_offset_.y) / size_.y) + ppo_;
        return Vec3f(tan_half_ * (1.f - 2.f * s.x), tan_half_ * (1.f - 2.f * s.y) / aspect_, 1.f);
    }
    // The inverse: the film position (pixels) of the camera-space plane point (x, y, 1).
    template <typename T> Vec2<T> film_position_of(const T& x, const T& y) const {
        const T sx = T(0.5f) * (T(1.f) - x / T(tan_half_));
        const T sy = T(0.5f) * (T(1.f) - T(aspect_) * y / T(tan_half_));
        return Vec2<T>((sx - T(ppo_.x)) * T(size_.x) - T(crop_offset_.x),
                       (sy - T(ppo_.y)) * T(size_.y) - T(crop_offset_.y));
    }
    // Mitsuba's perspective importance W(d) = 1 / (A cos^3 θ) for a direction at cos θ to the axis
    // (integrates to 1 over the frame's solid angle), scaled to the crop window.
    float importance(float cos_theta) const {
        return crop_importance_scale() / (plane_area_ * cos_theta * cos_theta * cos_theta);
    }

    Vec3f origin_; // world-space center of projection
    float x_fov_ = 0.f, tan_half_ = 0.f;
    Vec2f ppo_;
    float plane_area_ = 1.f;
};

// The parameters perspective and thinlens share: the horizontal field of view for the film's full frame and the
// principal point offset; raises at `to_world` if the camera transform has a scale (as Mitsuba refuses it).
struct PerspectiveParameters {
    float x_fov;
    Vec2f principal_point_offset;
};
PerspectiveParameters load_perspective_parameters(const Properties& props, const Sensor& camera);

} // namespace penumbra
