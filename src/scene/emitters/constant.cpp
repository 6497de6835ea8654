// Constant environment (Mitsuba 3 `constant`): the same radiance from every direction at infinity.
//
// | name     | type     | default | meaning                              |
// |----------|----------|---------|--------------------------------------|
// | radiance | spectrum | 1       | emitted radiance (W m^-2 sr^-1)      |
#include "core/param.h"
#include "core/warp.h"
#include "scene/emitters/emitters.h"

#include <sstream>

namespace penumbra {

namespace {

class ConstantEmitter final : public EmitterBase<ConstantEmitter> {
public:
    explicit ConstantEmitter(const Color3f& radiance) : radiance_(radiance) {
        flags_ = EmitterInfinite;
        scene_bounds_ = {Vec3f(0.f), 1.f}; // Mitsuba's unit sphere until the scene is known
    }

    // Mitsuba enlarges the scene's bounding sphere by a relative RayEpsilon.
    void set_scene_bounds(const BoundingSphere& b) override {
        Emitter::set_scene_bounds({b.center, std::max(RayEpsilon, b.radius * (1.f + RayEpsilon))});
    }

    // Uniform sphere sampling: pdf = 1/(4 pi), weight = 4 pi L. The point lies beyond the bounding sphere and ref.
    std::pair<DirectionSample3f, Color3f> sample_direction(const Interaction3f& ref, const Vec2f& u) const override {
        const float radius = std::max(scene_bounds_.radius, norm(ref.p - scene_bounds_.center));
        DirectionSample3f ds;
        ds.d = warp::square_to_uniform_sphere(u);
        ds.dist = 2.f * radius;
        ds.p = ref.p + ds.d * ds.dist;
        ds.n = -ds.d;
        ds.pdf = warp::square_to_uniform_sphere_pdf();
        ds.delta = false;
        ds.emitter = this;
        return {ds, radiance_ / ds.pdf};
    }

    // Origin uniform on the bounding sphere (pdf 1/(4 pi r^2)), cosine-weighted inward direction (pdf cos/pi):
    // weight = L cos / (pdf_A pdf_dir) = 4 pi^2 r^2 L.
    std::pair<Ray, Color3f> sample_ray(const Vec2f& u_position, const Vec2f& u_direction) const override {
        const Vec3f v = warp::square_to_uniform_sphere(u_position);
        const Vec3f d = Frame3f(-v).to_world(warp::square_to_cosine_hemisphere(u_direction));
        const float r = scene_bounds_.radius;
        return {Ray(scene_bounds_.center + v * r, d), radiance_ * (4.f * Pi * Pi * r * r)};
    }

    template <typename T> T pdf_direction_t(const Interaction<T>&, const DirectionSample<T>&) const {
        return T(Inv4Pi);
    }
    template <typename T> Color3<T> eval_t(const SurfaceInteraction<T>&) const { return Color3<T>(T(0)); }
    template <typename T> Color3<T> eval_environment_t(const Vec3<T>&) const {
        return param_color<T>(radiance_, index_);
    }

    // Power entering the bounding sphere: pi * 4 pi r^2 * L.
    Color3f power() const override {
        const float r = scene_bounds_.radius;
        return radiance_ * (4.f * Pi * Pi * r * r);
    }

    std::string to_string() const override {
        std::ostringstream os;
        os << "ConstantEmitter[radiance = " << radiance_ << "]";
        return os.str();
    }

    // Mitsuba's key (its radiance is a texture).
    void traverse(ParamVisitor& v) override { v.put("radiance.value", &radiance_.x, 3, &index_); }

private:
    Color3f radiance_;
    int index_ = -1;
};

} // namespace

std::shared_ptr<Emitter> make_constant_emitter(const Properties& props) {
    const Color3f radiance = get_emission(props, "radiance");
    return std::make_shared<ConstantEmitter>(radiance);
}

} // namespace penumbra
