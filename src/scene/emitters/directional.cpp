// Distant directional light (Mitsuba 3 `directional`): parallel light along one direction.
//
// | name       | type      | default  | meaning                                                           |
// |------------|-----------|----------|-------------------------------------------------------------------|
// | irradiance | spectrum  | 1        | irradiance on a surface perpendicular to the direction (W m^-2)   |
// | direction  | vector    | -        | world direction the light travels in (exclusive with to_world)   |
// | to_world   | transform | identity | emitter-to-world transform; the light travels along local +z      |
#include "core/warp.h"
#include "core/param.h"
#include "scene/emitters/emitters.h"

#include <sstream>

namespace penumbra {

namespace {

class DirectionalEmitter final : public EmitterBase<DirectionalEmitter> {
public:
    DirectionalEmitter(const Vec3f& direction, const Color3f& irradiance) : d_(direction), irradiance_(irradiance) {
        flags_ = EmitterInfinite | EmitterDeltaDirection;
        scene_bounds_ = {Vec3f(0.f), 1.f}; // Mitsuba's unit sphere until the scene is known
    }

    // Mitsuba enlarges the scene's bounding sphere by a relative RayEpsilon.
    void set_scene_bounds(const BoundingSphere& b) override {
        Emitter::set_scene_bounds({b.center, std::max(RayEpsilon, b.radius * (1.f + RayEpsilon))});
    }

    // Delta direction: the light arrives from -d with discrete pdf 1; weight = E. The sample point lies outside
    // the bounding sphere (and outside a reference point beyond it, e.g. the camera).
    std::pair<DirectionSample3f, Color3f> sample_direction(const Interaction3f& ref, const Vec2f&) const override {
        const float radius = std::max(scene_bounds_.radius, norm(ref.p - scene_bounds_.center));
        DirectionSample3f ds;
        ds.dist = 2.f * radius;
        ds.d = -d_;
        ds.p = ref.p - d_ * ds.dist;
        ds.n = d_;
        ds.pdf = 1.f;
        ds.delta = true;
        ds.emitter = this;
        return {ds, irradiance_};
    }

    // Origin uniform on the disk of the bounding sphere's radius perpendicular to d (pdf 1/(pi r^2)), placed
    // upstream of the sphere: weight = E * pi r^2.
    std::pair<Ray, Color3f> sample_ray(const Vec2f& u_position, const Vec2f&) const override {
        const Vec2f offset = warp::square_to_uniform_disk_concentric(u_position);
        const Vec3f perpendicular = Frame3f(d_).to_world(Vec3f(offset.x, offset.y, 0.f));
        const float r = scene_bounds_.radius;
        const Vec3f origin = scene_bounds_.center + (perpendicular - d_) * r;
        return {Ray(origin, d_), irradiance_ * (Pi * r * r)};
    }

    template <typename T> T pdf_direction_t(const Interaction<T>&, const DirectionSample<T>&) const { return T(0); }
    template <typename T> Color3<T> eval_t(const SurfaceInteraction<T>&) const { return Color3<T>(T(0)); }
    // A delta direction is never hit by an escaped ray.
    template <typename T> Color3<T> eval_environment_t(const Vec3<T>&) const { return Color3<T>(T(0)); }

    // Power through the scene: E * pi r^2 of the bounding sphere.
    Color3f power() const override { return irradiance_ * (Pi * scene_bounds_.radius * scene_bounds_.radius); }

    std::string to_string() const override {
        std::ostringstream os;
        os << "DirectionalEmitter[direction = " << d_ << ", irradiance = " << irradiance_ << "]";
        return os.str();
    }

    // Eq. 27 of paper 001: the irradiance E arriving along the light's direction (visibility is tested apart).
    template <typename T> Color3<T> eval_delta_t(const Vec3<T>&) const { return param_color<T>(irradiance_, index_); }
    void traverse(ParamVisitor& v) override { v.put("irradiance.value", &irradiance_.x, 3, &index_); }
    // A rotation taking local +z to d (the frame's s, t, n as columns).
    bool movable() const override { return true; }
    Transform to_world() const override {
        const Frame3f f(d_);
        Matrix4 m = Matrix4::identity();
        for (int r = 0; r < 3; ++r)
            m.m[r][0] = f.s[r], m.m[r][1] = f.t[r], m.m[r][2] = f.n[r];
        return Transform(m, m.transpose());
    }
    void set_to_world(const Transform& t) override { d_ = normalize(t.apply_vector(Vec3f(0.f, 0.f, 1.f))); }

  private:
    int index_ = -1;
    Vec3f d_; // unit world direction of propagation
    Color3f irradiance_;
};

} // namespace

std::shared_ptr<Emitter> make_directional_emitter(const Properties& props) {
    if (props.has("direction") && props.has("to_world"))
        props.raise("direction", "only one of 'direction' and 'to_world' can be specified");
    const Vec3f d = props.has("direction") ? props.get_vector("direction")
                                           : props.get_transform("to_world").apply_vector(Vec3f(0.f, 0.f, 1.f));
    if (!(norm(d) > 0.f)) props.raise(props.has("direction") ? "direction" : "to_world", "the light direction is zero");
    const Color3f irradiance = get_emission(props, "irradiance");
    return std::make_shared<DirectionalEmitter>(normalize(d), irradiance);
}

} // namespace penumbra
