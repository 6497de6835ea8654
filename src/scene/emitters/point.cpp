// Point light (Mitsuba 3 `point`): isotropic radiant intensity from one point.
//
// | name      | type      | default  | meaning                                              |
// |-----------|-----------|----------|------------------------------------------------------|
// | intensity | spectrum  | 1        | radiant intensity (W sr^-1)                          |
// | position  | point     | (0,0,0)  | light position (exclusive with to_world)             |
// | to_world  | transform | identity | emitter-to-world transform; the light sits at its origin |
#include "core/warp.h"
#include "core/param.h"
#include "scene/emitters/emitters.h"

#include <sstream>

namespace penumbra {

namespace {

class PointEmitter final : public EmitterBase<PointEmitter> {
public:
    PointEmitter(const Vec3f& position, const Color3f& intensity) : position_(position), intensity_(intensity) {
        flags_ = EmitterDeltaPosition;
    }

    // Delta position: the "pdf" is the discrete probability 1, weight = I / dist^2.
    std::pair<DirectionSample3f, Color3f> sample_direction(const Interaction3f& ref, const Vec2f&) const override {
        const DirectionSample3f ds = delta_position_sample(this, position_, ref);
        return {ds, intensity_ / (ds.dist * ds.dist)};
    }

    // Uniform direction (pdf 1/(4 pi)): weight = 4 pi I.
    std::pair<Ray, Color3f> sample_ray(const Vec2f&, const Vec2f& u_direction) const override {
        return {Ray(position_, warp::square_to_uniform_sphere(u_direction)), intensity_ * (4.f * Pi)};
    }
    float pdf_emission_direction(const Vec3f&) const override { return warp::square_to_uniform_sphere_pdf(); }

    template <typename T> T pdf_direction_t(const Interaction<T>&, const DirectionSample<T>&) const { return T(0); }
    template <typename T> Color3<T> eval_t(const SurfaceInteraction<T>&) const { return Color3<T>(T(0)); }
    template <typename T> Color3<T> eval_environment_t(const Vec3<T>&) const { return Color3<T>(T(0)); }

    Color3f power() const override { return intensity_ * (4.f * Pi); }

    std::string to_string() const override {
        std::ostringstream os;
        os << "PointEmitter[position = " << position_ << ", intensity = " << intensity_ << "]";
        return os.str();
    }

    // Eq. 24 of paper 001: the point light's incident term I / |p - x_src|² at p.
    template <typename T> Color3<T> eval_delta_t(const Vec3<T>& p) const {
        return param_color<T>(intensity_, index_) / squared_norm(Vec3<T>(position_) - p);
    }
    void traverse(ParamVisitor& v) override { v.put("intensity.value", &intensity_.x, 3, &index_); }
    bool movable() const override { return true; }
    Transform to_world() const override { return Transform::translate(position_); }
    void set_to_world(const Transform& t) override { position_ = t.apply_point(Vec3f(0.f)); }

  private:
    int index_ = -1;
    Vec3f position_;
    Color3f intensity_;
};

} // namespace

std::shared_ptr<Emitter> make_point_emitter(const Properties& props) {
    if (props.has("position") && props.has("to_world"))
        props.raise("position", "only one of 'position' and 'to_world' can be specified");
    const Vec3f position = props.has("position") ? props.get_vector("position")
                                                 : props.get_transform("to_world").apply_point(Vec3f(0.f));
    const Color3f intensity = get_emission(props, "intensity");
    return std::make_shared<PointEmitter>(position, intensity);
}

} // namespace penumbra
