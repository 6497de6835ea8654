// Area light (Mitsuba 3 `area`): diffuse emission from the front side of the parent shape.
//
// | name     | type            | default | meaning                                    |
// |----------|-----------------|---------|--------------------------------------------|
// | radiance | spectrum/texture| 1       | emitted radiance (W m^-2 sr^-1)            |
//
// A `to_world` is rejected as in Mitsuba: the light inherits the shape's transform.
//
// Front side: Mitsuba decides it with the shading frame (`cos_theta(si.wi) > 0`) in `eval` and with the sampled
// normal in `sample_direction`. penumbra uses the geometric normal (triangle winding) in both `eval`,
// `sample_direction` and `pdf_direction`, so that the set of directions in which the light is visible is the same
// for BSDF sampling and for emitter sampling (a requirement for unbiased MIS); it differs from Mitsuba only at
// grazing angles on smooth-shaded meshes.
#include "core/warp.h"
#include "core/param.h"
#include "scene/emitters/emitters.h"
#include "scene/shape.h"
#include "scene/texture.h"

#include <sstream>

namespace penumbra {

namespace {

class AreaEmitter final : public EmitterBase<AreaEmitter> {
public:
    explicit AreaEmitter(std::shared_ptr<Texture> radiance)
        : radiance_(std::move(radiance)), constant_(radiance_->is_constant()) {
        flags_ = EmitterSurface;
    }

    // L_e at a point of the shape, as a surface interaction with a frame around the geometric normal.
    Color3f radiance_at(const PositionSample3f& ps, const Vec3f& wo_world) const {
        if (constant_) return radiance_->mean(); // the value eval() would return, without the interaction
        SurfaceInteraction3f si;
        si.t = 0.f;
        si.p = ps.p;
        si.n = ps.n;
        si.uv = ps.uv;
        si.sh_frame = Frame3f(ps.n);
        si.wi = si.to_local(wo_world);
        si.shape = shape_;
        return radiance_->eval(si);
    }

    // Area sampling converted to solid angle at ref: pdf = pdf_A * dist^2 / |cos theta_e|, weight = L_e / pdf.
    std::pair<DirectionSample3f, Color3f> sample_direction(const Interaction3f& ref, const Vec2f& u) const override {
        if (!shape_) return {DirectionSample3f(), Color3f(0.f)}; // not attached to a shape: emits nothing
        const PositionSample3f ps = shape_->sample_position(u);
        DirectionSample3f ds;
        ds.p = ps.p;
        ds.n = ps.n;
        ds.uv = ps.uv;
        ds.prim = ps.prim;
        ds.bary = ps.bary;
        ds.delta = false;
        ds.emitter = this;
        const Vec3f to_light = ps.p - ref.p;
        const float dist2 = squared_norm(to_light);
        ds.dist = std::sqrt(dist2);
        ds.d = to_light / ds.dist;
        const float cos_emitter = -dot(ds.d, ps.n);
        if (!(cos_emitter > 0.f) || !(dist2 > 0.f)) return {ds, Color3f(0.f)}; // ref behind the emitter
        ds.pdf = ps.pdf * dist2 / cos_emitter;
        return {ds, radiance_at(ps, -ds.d) / ds.pdf};
    }

    // Position by area (pdf 1/A), cosine-weighted direction on the front side (pdf cos/pi):
    // weight = L_e cos / (pdf_A pdf_dir) = pi L_e / pdf_A.
    std::pair<Ray, Color3f> sample_ray(const Vec2f& u_position, const Vec2f& u_direction) const override {
        if (!shape_) return {Ray(), Color3f(0.f)};
        const PositionSample3f ps = shape_->sample_position(u_position);
        const Vec3f local = warp::square_to_cosine_hemisphere(u_direction);
        const Vec3f d = Frame3f(ps.n).to_world(local);
        Interaction3f origin;
        origin.p = ps.p;
        origin.n = ps.n;
        Ray ray = origin.spawn_ray(d);
        return {ray, radiance_at(ps, d) * (Pi / ps.pdf)};
    }

    template <typename T> T pdf_direction_t(const Interaction<T>&, const DirectionSample<T>& ds) const {
        const T cos_emitter = -dot(ds.d, ds.n);
        if (!shape_ || !(cos_emitter > T(0))) return T(0);
        return T(shape_->pdf_position()) * ds.dist * ds.dist / cos_emitter;
    }

    // Radiance toward si.wi, on the side of the geometric normal si.n only.
    template <typename T> Color3<T> eval_t(const SurfaceInteraction<T>& si) const {
        if (!(dot(si.to_world(si.wi), si.n) > T(0))) return Color3<T>(T(0));
        return radiance_->eval(si);
    }

    template <typename T> Color3<T> eval_environment_t(const Vec3<T>&) const { return Color3<T>(T(0)); }

    // Phi = pi * A * mean(L_e).
    Color3f power() const override { return shape_ ? radiance_->mean() * (Pi * shape_->surface_area()) : Color3f(0.f); }

    std::string to_string() const override {
        std::ostringstream os;
        os << "AreaEmitter[radiance mean = " << radiance_->mean()
           << ", area = " << (shape_ ? shape_->surface_area() : 0.f) << "]";
        return os.str();
    }

    void traverse(ParamVisitor& v) override { v.put_object("radiance", radiance_.get()); }

private:
    std::shared_ptr<Texture> radiance_;
    bool constant_; // a constant radiance texture
};

} // namespace

std::shared_ptr<Emitter> make_area_emitter(const Properties& props) {
    if (props.has("to_world"))
        props.raise("to_world", "an area light inherits its transform from its parent shape; 'to_world' is not allowed");
    std::shared_ptr<Texture> radiance = props.get_texture("radiance", Color3f(1.f));
    if (radiance->is_constant()) check_emission(props, "radiance", radiance->mean());
    return std::make_shared<AreaEmitter>(std::move(radiance));
}

} // namespace penumbra
