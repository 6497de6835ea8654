// Point light (Mitsuba 3 `point`): isotropic radiant intensity from one point.
//
// | name      | type      | default  | meaning                                              |
// |-----------|-----------|----------|------------------------------------------------------|
// | intensity | spectrum  | 1        | radiant intensity (W sr^-1)                          |
// | position  | point     | (0,0,0)  | light position (exclusive with to_world)             |
// | to_world  | transform | identity | emitter-to-world transform; the light sits at its origin |
#include "core/warp.h"
#include "scene/emitter.h"
#include "scene/properties.h"

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
        DirectionSample3f ds;
        ds.p = position_;
        ds.n = Vec3f(0.f);
        ds.pdf = 1.f;
        ds.delta = true;
        ds.emitter = this;
        const Vec3f to_light = position_ - ref.p;
        ds.dist = norm(to_light);
        ds.d = to_light / ds.dist;
        return {ds, intensity_ / (ds.dist * ds.dist)};
    }

    // Uniform direction (pdf 1/(4 pi)): weight = 4 pi I.
    std::pair<Ray, Color3f> sample_ray(const Vec2f&, const Vec2f& u_direction) const override {
        return {Ray(position_, warp::square_to_uniform_sphere(u_direction)), intensity_ * (4.f * Pi)};
    }

    template <typename T> T pdf_direction_t(const Interaction<T>&, const DirectionSample<T>&) const { return T(0); }
    template <typename T> Color3<T> eval_t(const SurfaceInteraction<T>&) const { return Color3<T>(T(0)); }
    template <typename T> Color3<T> eval_environment_t(const Vec3<T>&) const { return Color3<T>(T(0)); }

    Color3f power() const override { return intensity_ * (4.f * Pi); }

    std::string to_string() const override {
        std::ostringstream os;
        os << "PointEmitter[position = " << position_ << ", intensity = " << intensity_ << "]";
        return os.str();
    }

private:
    Vec3f position_;
    Color3f intensity_;
};

} // namespace

std::shared_ptr<Emitter> make_point_emitter(const Properties& props) {
    if (props.has("position") && props.has("to_world"))
        props.raise("position", "only one of 'position' and 'to_world' can be specified");
    const Vec3f position = props.has("position") ? props.get_vector("position")
                                                 : props.get_transform("to_world").apply_point(Vec3f(0.f));
    const Color3f intensity = props.get_color("intensity", Color3f(1.f));
    if (!is_finite(intensity) || intensity.x < 0.f || intensity.y < 0.f || intensity.z < 0.f)
        props.raise("intensity", "'intensity' must be finite and non-negative");
    return std::make_shared<PointEmitter>(position, intensity);
}

} // namespace penumbra
