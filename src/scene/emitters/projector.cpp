// Projector (Mitsuba 3 `projector`): a pinhole camera run in reverse, a delta-position light that projects an
// image into the scene.
//
// | name         | type      | default  | meaning                                                        |
// |--------------|-----------|----------|----------------------------------------------------------------|
// | irradiance   | texture   | required | image projected (bitmap, or a constant rgb/spectrum), see below |
// | scale        | float     | 1        | factor applied to the irradiance values                        |
// | fov          | float     | -        | field of view in degrees along fov_axis, in (0, 180)           |
// | fov_axis     | string    | x        | x | y | diagonal | smaller | larger (only with fov)           |
// | focal_length | string    | 50mm     | 35mm-film-equivalent focal length (when fov is absent)         |
// | to_world     | transform | identity | projector-to-world transform (looks along local +z)            |
//
// Geometry (the perspective camera's, sensors/perspective.cpp): local +z forward, +x left, +y up; the image
// has the texture's aspect W / H (1 for a constant) and a point q (local) maps to
//     uv = (1/2 (1 - q.x / (q.z t)), 1/2 (1 - aspect q.y / (q.z t))),   t = tan(fov_x / 2),
// uv = (0, 0) being the image's top-left texel. Outside [0, 1]² (and behind the projector) there is no light.
//
// Units (Mitsuba's normalization): a texel value E is the irradiance on the virtual image plane z = 1, up to
// Mitsuba's factor pi: a plane perpendicular to the axis at distance z receives the irradiance
// pi scale E(uv) / z² (so a constant texture lights such a plane uniformly), and a white diffuse plane at z =
// 1 shows the radiance scale E. The incident term at p (what I / d² is for a point light) is
//     pi scale E(uv) / (d² cos³ θ),   d = |q|, cos θ = q.z / |q|.
#include "core/param.h"
#include "scene/emitters/emitters.h"
#include "scene/mesh.h"
#include "scene/sensors/sensor_common.h"
#include "scene/texture.h"

#include <array>
#include <sstream>

namespace penumbra {

namespace {

class ProjectorEmitter final : public EmitterBase<ProjectorEmitter> {
  public:
    ProjectorEmitter(const Transform& to_world, std::shared_ptr<Texture> irradiance, float scale,
                     float x_fov_deg)
        : to_world_(to_world), to_local_(to_world.inverse()), position_(to_world.apply_point(Vec3f(0.f))),
          irradiance_(std::move(irradiance)), scale_(scale), tan_half_(std::tan(0.5f * radians(x_fov_deg))) {
        const Vec2i size = irradiance_->resolution();
        aspect_ = float(size.x) / float(size.y);
        plane_area_ = 4.f * tan_half_ * tan_half_ / aspect_;
        flags_ = EmitterDeltaPosition;
    }

    // The image coordinates of the local point q (valid for q.z > 0).
    template <typename T> Vec2<T> image_uv(const Vec3<T>& q) const {
        return {T(0.5f) * (T(1.f) - q.x / (q.z * T(tan_half_))),
                T(0.5f) * (T(1.f) - T(aspect_) * q.y / (q.z * T(tan_half_)))};
    }

    // pi scale E(uv) / (d² cos³ θ) = pi scale E(uv) |q| / q.z³ at the world point p (0 outside the frustum).
    template <typename T> Color3<T> eval_delta_t(const Vec3<T>& p) const {
        using std::sqrt;
        const Vec3<T> q = to_local_.apply_point(p);
        if (!(q.z > T(0))) return Color3<T>(T(0));
        SurfaceInteraction<T> si;
        si.uv = image_uv(q);
        if (!(si.uv.x >= T(0) && si.uv.x <= T(1) && si.uv.y >= T(0) && si.uv.y <= T(1)))
            return Color3<T>(T(0));
        const T z3 = q.z * q.z * q.z;
        return irradiance_->eval(si) *
               (param_value<T>(scale_, scale_index_) * T(Pi) * sqrt(squared_norm(q)) / z3);
    }

    // Delta position: the weight is the incident term with the discrete pdf 1.
    std::pair<DirectionSample3f, Color3f> sample_direction(const Interaction3f& ref,
                                                           const Vec2f&) const override {
        const DirectionSample3f ds = delta_position_sample(this, position_, ref);
        return {ds, eval_delta_t<float>(ref.p)};
    }

    // A point of the image plane z = 1, uniform by area (pdf 1 / A); toward q the intensity is pi scale E
    // |q|³ and dω = dA / |q|³, so the weight I / pdf_ω is pi scale E A (Mitsuba samples the texture instead).
    std::pair<Ray, Color3f> sample_ray(const Vec2f&, const Vec2f& u_direction) const override {
        const Vec3f q(tan_half_ * (1.f - 2.f * u_direction.x),
                      tan_half_ * (1.f - 2.f * u_direction.y) / aspect_, 1.f);
        SurfaceInteraction3f si;
        si.uv = u_direction;
        const Vec3f d = normalize(to_world_.apply_vector(q));
        return {Ray(position_, d), irradiance_->eval(si) * (scale_ * Pi * plane_area_)};
    }
    // The plane point q = d / d.z has area density 1 / A and dA = |q|³ dω: pdf_ω = 1 / (A d.z³) in the
    // frustum (d local and unit).
    float pdf_emission_direction(const Vec3f& d) const override {
        const Vec3f local = normalize(to_local_.apply_vector(d));
        if (!(local.z > 0.f)) return 0.f;
        const Vec2f uv = image_uv(local);
        if (!(uv.x >= 0.f && uv.x <= 1.f && uv.y >= 0.f && uv.y <= 1.f)) return 0.f;
        return 1.f / (plane_area_ * local.z * local.z * local.z);
    }

    template <typename T> T pdf_direction_t(const Interaction<T>&, const DirectionSample<T>&) const {
        return T(0);
    }
    template <typename T> Color3<T> eval_t(const SurfaceInteraction<T>&) const { return Color3<T>(T(0)); }
    template <typename T> Color3<T> eval_environment_t(const Vec3<T>&) const { return Color3<T>(T(0)); }

    // Phi = ∫ I dω = pi scale ∫_plane E dA = pi scale A mean(E).
    Color3f power() const override { return irradiance_->mean() * (scale_ * Pi * plane_area_); }

    // The frustum's border is a jump of the light; a mesh strictly inside it (all vertices: the frustum is
    // convex) or entirely outside one of its side planes does not meet it. Texel edges of a nearest-filtered
    // image jump too.
    bool emission_jumps_on(const TriangleMesh& mesh) const override {
        if (!irradiance_->is_continuous()) return true;
        // Side planes, inside when positive: q.z t ∓ q.x and q.z t / aspect ∓ q.y.
        std::array<int, 4> inside{};
        for (const Vec3f& p : mesh.positions) {
            const Vec3f q = to_local_.apply_point(p);
            const float hx = q.z * tan_half_, hy = q.z * tan_half_ / aspect_;
            const std::array<float, 4> side{hx - q.x, hx + q.x, hy - q.y, hy + q.y};
            for (int k = 0; k < 4; ++k)
                inside[k] += side[k] > 0.f;
        }
        const int n = int(mesh.positions.size());
        bool all_inside = true;
        for (int k = 0; k < 4; ++k) {
            if (inside[k] == 0) return false;
            all_inside = all_inside && inside[k] == n;
        }
        return !all_inside;
    }

    std::string to_string() const override {
        std::ostringstream os;
        os << "ProjectorEmitter[position = " << position_
           << ", x_fov = " << degrees(2.f * std::atan(tan_half_)) << ", scale = " << scale_
           << ", irradiance = " << irradiance_->to_string() << "]";
        return os.str();
    }

    bool movable() const override { return true; }
    Transform to_world() const override { return to_world_; }
    void set_to_world(const Transform& t) override {
        to_world_ = t;
        to_local_ = t.inverse();
        position_ = t.apply_point(Vec3f(0.f));
    }

    void traverse(ParamVisitor& v) override {
        v.put_object("irradiance", irradiance_.get());
        v.put("scale", &scale_, 1, &scale_index_);
    }

  private:
    Transform to_world_, to_local_;
    Vec3f position_;
    std::shared_ptr<Texture> irradiance_;
    float scale_;
    int scale_index_ = -1;
    float tan_half_, aspect_ = 1.f, plane_area_ = 0.f;
};

} // namespace

std::shared_ptr<Emitter> make_projector_emitter(const Properties& props) {
    std::shared_ptr<Texture> irradiance = props.get_texture("irradiance");
    const float scale = props.get_float("scale", 1.f);
    if (!std::isfinite(scale) || scale < 0.f) props.raise("scale", "'scale' must be finite and non-negative");
    if (irradiance->is_constant()) check_emission(props, "irradiance", irradiance->mean());
    const Vec2i size = irradiance->resolution();
    const float x_fov = parse_x_fov(props, double(size.x) / double(size.y));
    return std::make_shared<ProjectorEmitter>(props.get_transform("to_world"), std::move(irradiance), scale,
                                              x_fov);
}

} // namespace penumbra
