// Mitsuba 3 `perspective` (pinhole) camera.
//
// Parameters (plus the common sensor parameters, see sensors/factory.cpp):
//   fov                       float   --      field of view in degrees along fov_axis, in (0, 180)
//   fov_axis                  string  x       x | y | diagonal | smaller | larger (only with fov)
//   focal_length              string  50mm    35mm-film-equivalent focal length (when fov is absent)
//   principal_point_offset_x  float   0       principal point shift, in units of the film width
//   principal_point_offset_y  float   0       principal point shift, in units of the film height
//
// Camera space: looks along +z, +x is left, +y up (Transform::look_at). A film position (px, py) in pixels,
// (0, 0) = top-left, maps to s = (px / W, py / H) + principal_point_offset and to the direction
//   d_local ~ (tan(fov_x / 2) (1 - 2 s_x), tan(fov_x / 2) (1 - 2 s_y) / aspect, 1),   aspect = W / H.
#include "scene/sensors/sensor_common.h"

#include <cmath>
#include <cstdlib>

namespace penumbra {

// Mitsuba's parse_fov(): the horizontal field of view in degrees.
float parse_x_fov(const Properties& props, double aspect) {
    if (props.has("fov") && props.has("focal_length"))
        props.raise("focal_length",
                    "specify either a focal length ('focal_length') or a field of view ('fov')");
    double fov;
    std::string axis;
    if (props.has("fov")) {
        fov = props.get_float("fov");
        axis = props.get_string("fov_axis", "x");
        if (axis == "smaller")
            axis = aspect > 1 ? "y" : "x";
        else if (axis == "larger")
            axis = aspect > 1 ? "x" : "y";
    } else {
        std::string f = props.get_string("focal_length", "50mm");
        if (f.size() > 2 && f.compare(f.size() - 2, 2, "mm") == 0) f.resize(f.size() - 2);
        char* end = nullptr;
        const double value = std::strtod(f.c_str(), &end);
        if (f.empty() || *end != '\0' || !(value > 0))
            props.raise("focal_length", "could not parse the focal length (expected '<x>mm' with x > 0)");
        // Diagonal of 35mm film (36 x 24 mm) seen at distance `value`.
        fov = 2.0 * std::atan(std::sqrt(36.0 * 36.0 + 24.0 * 24.0) / (2.0 * value)) * 180.0 / Pi;
        axis = "diagonal";
    }
    const double half = 0.5 * fov * Pi / 180.0;
    double result;
    if (axis == "x") {
        result = fov;
    } else if (axis == "y") {
        result = 2.0 * std::atan(std::tan(half) * aspect) * 180.0 / Pi;
    } else if (axis == "diagonal") {
        const double width = 2.0 * std::tan(half) / std::sqrt(1.0 + 1.0 / (aspect * aspect));
        result = 2.0 * std::atan(0.5 * width) * 180.0 / Pi;
    } else {
        props.raise("fov_axis",
                    "invalid fov_axis '" + axis + "' (expected 'x', 'y', 'diagonal', 'smaller' or 'larger')");
    }
    if (!(result > 0.0 && result < 180.0))
        props.raise(props.has("fov") ? "fov" : "focal_length",
                    "the horizontal field of view must be in (0, 180) degrees");
    return float(result);
}

namespace {

// Mitsuba's Transform::has_scale(): the linear part is not orthonormal (M M^T != I within 1e-3).
bool has_scale(const Transform& t) {
    const auto& m = t.matrix.m;
    for (int i = 0; i < 3; ++i)
        for (int j = i; j < 3; ++j) {
            const float sum = m[i][0] * m[j][0] + m[i][1] * m[j][1] + m[i][2] * m[j][2];
            if (std::abs(sum - (i == j ? 1.f : 0.f)) > 1e-3f) return true;
        }
    return false;
}

class PerspectiveCamera final : public SensorBase<PerspectiveCamera, ProjectiveCamera> {
  public:
    // Called once the film and the transform are set.
    void configure(float x_fov_deg, const Vec2f& principal_point_offset) {
        configure_projection();
        x_fov_ = x_fov_deg;
        tan_half_ = std::tan(0.5f * radians(x_fov_deg));
        ppo_ = principal_point_offset;
        origin_ = to_world.apply_point(Vec3f(0.f));
        // Image-plane area at distance 1: (2 tan(fov_x / 2)) x (2 tan(fov_x / 2) / aspect).
        plane_area_ = 4.f * tan_half_ * tan_half_ / aspect_;
    }

    std::pair<Ray, Color3f> sample_ray(const Vec2f& film_pos, const Vec2f&) const override {
        const Vec2f s = Vec2f(film_pos.x / size_.x, film_pos.y / size_.y) + ppo_;
        const Vec3f local =
            normalize(Vec3f(tan_half_ * (1.f - 2.f * s.x), tan_half_ * (1.f - 2.f * s.y) / aspect_, 1.f));
        return {Ray(origin_, normalize(to_world.apply_vector(local)), far_clip / local.z), Color3f(1.f)};
    }

    bool project(const Vec3f& p, Vec2f& film_pos) const override {
        const Vec3f q = to_local_.apply_point(p);
        if (!(q.z >= near_clip && q.z <= far_clip)) return false;
        const float sx = 0.5f * (1.f - q.x / (q.z * tan_half_));
        const float sy = 0.5f * (1.f - aspect_ * q.y / (q.z * tan_half_));
        film_pos = Vec2f((sx - ppo_.x) * size_.x, (sy - ppo_.y) * size_.y);
        return on_film(film_pos);
    }

    // Pinhole importance W(d) = 1 / (A cos^3 theta) (Mitsuba's importance(): includes the image-plane
    // foreshortening, so that the integral of W over the solid angle of the film is 1); weight = W / dist^2.
    std::pair<DirectionSample3f, Color3f> sample_direction(const Interaction3f& ref,
                                                           const Vec2f&) const override {
        DirectionSample3f ds;
        Vec2f film_pos;
        if (!project(ref.p, film_pos)) return {ds, Color3f(0.f)};
        const Vec3f to_camera = origin_ - ref.p;
        const float dist = norm(to_camera);
        const float cos_theta = to_local_.apply_point(ref.p).z / dist;
        ds.p = origin_;
        ds.n = forward_;
        ds.uv = film_pos;
        ds.d = to_camera / dist;
        ds.dist = dist;
        ds.pdf = 1.f;
        ds.delta = true;
        const float importance = 1.f / (plane_area_ * cos_theta * cos_theta * cos_theta);
        return {ds, Color3f(importance / (dist * dist))};
    }

    void set_transform(const Transform& t) override {
        to_world = t;
        configure(x_fov_, ppo_);
    }

    // s(p) as in project(), and |ds/dA| = (W H / A) cos θ_p / (d² cos³ θ_c): pixels per unit solid angle
    // (W H / A / cos³ θ_c, A the image-plane area at distance 1) times dω/dA = cos θ_p / d².
    template <typename T> bool film_position_t(const Vec3<T>& p, const Vec3<T>& n, Vec2<T>& film_pos, T& jacobian) const {
        using std::abs;
        using std::sqrt;
        const Vec3<T> q = to_local_.apply_point(p);
        if (!(detach(q.z) > 0.f)) return false;
        const T sx = T(0.5f) * (T(1.f) - q.x / (q.z * T(tan_half_)));
        const T sy = T(0.5f) * (T(1.f) - T(aspect_) * q.y / (q.z * T(tan_half_)));
        film_pos = Vec2<T>((sx - T(ppo_.x)) * T(size_.x), (sy - T(ppo_.y)) * T(size_.y));
        const Vec3<T> d = p - Vec3<T>(origin_);
        const T dist2 = squared_norm(d);
        const T dist = sqrt(dist2);
        const T cos_c = q.z / dist;
        const T cos_p = abs(dot(n, d)) / dist;
        jacobian = T(size_.x * size_.y / plane_area_) * cos_p / (dist2 * cos_c * cos_c * cos_c);
        return true;
    }
    template <typename T> Vec3<T> to_sensor_t(const Vec3<T>& p) const { return normalize(Vec3<T>(origin_) - p); }

    std::string to_string() const override {
        return "PerspectiveCamera[x_fov=" + std::to_string(x_fov_) + ", film=" + film->to_string() + "]";
    }

  private:
    float x_fov_ = 0.f, tan_half_ = 0.f;
    Vec2f ppo_;
    float plane_area_ = 1.f;
    Vec3f origin_;
};

} // namespace

std::shared_ptr<Sensor> make_perspective_sensor(const Properties& props, const LoadContext& ctx) {
    auto camera = std::make_shared<PerspectiveCamera>();
    load_sensor_common(*camera, props, ctx);
    if (has_scale(camera->to_world))
        props.raise("to_world", "scale factors in the camera-to-world transformation are not allowed");
    const float x_fov = parse_x_fov(props, double(camera->film->width) / camera->film->height);
    const Vec2f ppo(props.get_float("principal_point_offset_x", 0.f),
                    props.get_float("principal_point_offset_y", 0.f));
    camera->configure(x_fov, ppo);
    return camera;
}

} // namespace penumbra
