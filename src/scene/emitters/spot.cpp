// Spot light (Mitsuba 3 `spot`): a point light emitting along local +z with a linear angular falloff.
//
// | name         | type      | default            | meaning                                           |
// |--------------|-----------|--------------------|---------------------------------------------------|
// | intensity    | spectrum  | 1                  | radiant intensity at the beam center (W sr^-1)    |
// | cutoff_angle | float     | 20                 | angle (degrees) beyond which the light is black   |
// | beam_width   | float     | 3/4 cutoff_angle   | angle (degrees) of the full-intensity beam         |
// | to_world     | transform | identity           | emitter-to-world transform (light at its origin)  |
// | texture      | texture   | -                  | projected texture, multiplies the intensity (below) |
//
// The texture covers the cutoff cone's square of directions, as in Mitsuba: a local direction d maps to
//     uv = (1/2 + d.x / (2 d.z tan(cutoff)), 1/2 + d.y / (2 d.z tan(cutoff))),
// and a texture that is not spatially varying (a constant) is ignored, as Mitsuba does.
#include "core/param.h"
#include "core/warp.h"
#include "scene/emitters/emitters.h"
#include "scene/texture.h"

#include <sstream>

namespace penumbra {

namespace {

class SpotEmitter final : public EmitterBase<SpotEmitter> {
public:
    SpotEmitter(const Transform& to_world, const Color3f& intensity, float cutoff_deg, float beam_deg,
                std::shared_ptr<Texture> texture)
        : to_world_(to_world), position_(to_world.apply_point(Vec3f(0.f))), intensity_(intensity),
          cutoff_(radians(cutoff_deg)), beam_width_(radians(beam_deg)), cos_cutoff_(std::cos(cutoff_)),
          cos_beam_width_(std::cos(beam_width_)), uv_factor_(std::tan(cutoff_)), texture_(std::move(texture)) {
        flags_ = EmitterDeltaPosition;
    }

    // Mitsuba's falloff: 1 inside beam_width, (cutoff - theta) / (cutoff - beam_width) between beam_width and the
    // cutoff, 0 at and beyond the cutoff. `local` is a direction in the light's frame (not necessarily unit).
    template <typename T> T falloff(const Vec3<T>& local) const {
        using std::acos;
        const T cos_theta = normalize(local).z;
        if (!(cos_theta > T(cos_cutoff_))) return T(0);
        if (cos_theta >= T(cos_beam_width_)) return T(1);
        return (T(cutoff_) - acos(cos_theta)) / T(cutoff_ - beam_width_);
    }

    // The projected texture's value in the local direction `local` inside the cone (1 without a texture).
    template <typename T> Color3<T> texture_factor(const Vec3<T>& local) const {
        if (!texture_) return Color3<T>(T(1));
        SurfaceInteraction<T> si;
        si.uv = Vec2<T>(T(0.5f) + T(0.5f) * local.x / (local.z * T(uv_factor_)),
                        T(0.5f) + T(0.5f) * local.y / (local.z * T(uv_factor_)));
        return texture_->eval(si);
    }

    // The emitted intensity toward `local` relative to the beam center: falloff times the texture.
    template <typename T> Color3<T> profile(const Vec3<T>& local) const {
        const T f = falloff(local);
        if (!(f > T(0))) return Color3<T>(T(0));
        return texture_factor(local) * f;
    }

    // Delta position: weight = I * falloff / dist^2 with discrete pdf 1.
    std::pair<DirectionSample3f, Color3f> sample_direction(const Interaction3f& ref, const Vec2f&) const override {
        const DirectionSample3f ds = delta_position_sample(this, position_, ref);
        return {ds, intensity_ * profile(to_world_.inverse().apply_vector(-ds.d)) / (ds.dist * ds.dist)};
    }

    // Uniform direction in the cutoff cone: weight = I * falloff / pdf_cone.
    std::pair<Ray, Color3f> sample_ray(const Vec2f&, const Vec2f& u_direction) const override {
        const Vec3f local = warp::square_to_uniform_cone(u_direction, cos_cutoff_);
        const Vec3f d = normalize(to_world_.apply_vector(local));
        return {Ray(position_, d),
                intensity_ * profile(local) / warp::square_to_uniform_cone_pdf(cos_cutoff_)};
    }
    float pdf_emission_direction(const Vec3f& d) const override {
        const Vec3f local = normalize(to_world_.inverse().apply_vector(d));
        return local.z >= cos_cutoff_ ? warp::square_to_uniform_cone_pdf(cos_cutoff_) : 0.f;
    }

    template <typename T> T pdf_direction_t(const Interaction<T>&, const DirectionSample<T>&) const { return T(0); }
    template <typename T> Color3<T> eval_t(const SurfaceInteraction<T>&) const { return Color3<T>(T(0)); }
    template <typename T> Color3<T> eval_environment_t(const Vec3<T>&) const { return Color3<T>(T(0)); }

    // Phi = 2 pi I int_0^cutoff falloff(theta) sin(theta) dtheta
    //     = 2 pi I [1 + (sin(beam) - sin(cutoff)) / (cutoff - beam)]   (1 - cos(cutoff) when beam = cutoff).
    Color3f power() const override {
        const float width = cutoff_ - beam_width_;
        const float integral = width > 0.f ? 1.f + (std::sin(beam_width_) - std::sin(cutoff_)) / width : 1.f - cos_cutoff_;
        // With a texture, its mean stands for its average over the cone (an estimate: the report's power).
        return intensity_ * (2.f * Pi * integral) * (texture_ ? texture_->mean() : Color3f(1.f));
    }

    std::string to_string() const override {
        std::ostringstream os;
        os << "SpotEmitter[position = " << position_ << ", intensity = " << intensity_
           << ", cutoff_angle = " << degrees(cutoff_) << ", beam_width = " << degrees(beam_width_) << "]";
        return os.str();
    }

    // I falloff(ω) texture(uv(ω)) / |p - x_src|² at p.
    template <typename T> Color3<T> eval_delta_t(const Vec3<T>& p) const {
        const Vec3<T> d = p - Vec3<T>(position_);
        const T dist2 = squared_norm(d);
        using std::sqrt;
        const Vec3<T> local = to_world_.inverse().apply_vector(d / sqrt(dist2));
        return param_color<T>(intensity_, index_) * profile(local) / dist2;
    }
    void traverse(ParamVisitor& v) override {
        v.put("intensity.value", &intensity_.x, 3, &index_);
        if (texture_) v.put_object("texture", texture_.get());
    }
    bool movable() const override { return true; }
    Transform to_world() const override { return to_world_; }
    void set_to_world(const Transform& t) override {
        to_world_ = t;
        position_ = t.apply_point(Vec3f(0.f));
    }
    // Without a falloff ring (beam_width = cutoff_angle) the cone's border is a jump, and so are the texel
    // edges of a nearest-filtered texture.
    bool emission_jumps_on(const TriangleMesh&) const override {
        return !(beam_width_ < cutoff_) || (texture_ && !texture_->is_continuous());
    }

private:
    int index_ = -1;
    Transform to_world_;
    Vec3f position_;
    Color3f intensity_;
    float cutoff_, beam_width_, cos_cutoff_, cos_beam_width_, uv_factor_;
    std::shared_ptr<Texture> texture_; // null without a spatially varying texture
};

} // namespace

std::shared_ptr<Emitter> make_spot_emitter(const Properties& props) {
    const Color3f intensity = get_emission(props, "intensity");
    const float cutoff = props.get_float("cutoff_angle", 20.f);
    const float beam = props.get_float("beam_width", cutoff * 0.75f);
    if (!(cutoff > 0.f) || !(cutoff <= 180.f)) props.raise("cutoff_angle", "'cutoff_angle' must be in (0, 180] degrees");
    if (!(beam >= 0.f) || !(beam <= cutoff))
        props.raise("beam_width", "'beam_width' must be in [0, cutoff_angle] degrees");
    std::shared_ptr<Texture> texture = props.has("texture") ? props.get_texture("texture") : nullptr;
    if (texture && texture->is_constant()) texture = nullptr;
    return std::make_shared<SpotEmitter>(props.get_transform("to_world"), intensity, cutoff, beam,
                                         std::move(texture));
}

} // namespace penumbra
