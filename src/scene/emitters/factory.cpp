// make_emitter: Mitsuba 3 emitter plugins by `type`, and the helpers shared by the plugins. Each maker lives
// in the plugin's own file.
#include "scene/emitters/emitters.h"
#include "scene/medium.h"

namespace penumbra {

void check_emission(const Properties& props, const std::string& name, const Color3f& value) {
    if (!is_finite(value) || value.x < 0.f || value.y < 0.f || value.z < 0.f)
        props.raise(name, "'" + name + "' must be finite and non-negative");
}

Color3f get_emission(const Properties& props, const std::string& name) {
    const Color3f value = props.get_color(name, Color3f(1.f));
    check_emission(props, name, value);
    return value;
}

DirectionSample3f delta_position_sample(const Emitter* emitter, const Vec3f& position,
                                        const Interaction3f& ref) {
    DirectionSample3f ds;
    ds.p = position;
    ds.n = Vec3f(0.f);
    ds.pdf = 1.f;
    ds.delta = true;
    ds.emitter = emitter;
    const Vec3f to_light = position - ref.p;
    ds.dist = norm(to_light);
    ds.d = to_light / ds.dist;
    return ds;
}

namespace {

std::shared_ptr<Emitter> make_emitter_of_type(const Properties& props, const LoadContext& ctx) {
    const std::string& type = props.plugin();
    if (type == "area") return make_area_emitter(props);
    if (type == "point") return make_point_emitter(props);
    if (type == "spot") return make_spot_emitter(props);
    if (type == "projector") return make_projector_emitter(props);
    if (type == "directional") return make_directional_emitter(props);
    if (type == "constant") return make_constant_emitter(props);
    if (type == "envmap") return make_envmap_emitter(props, ctx);
    throw_unsupported_plugin(props, ObjectKind::Emitter);
}

} // namespace

// Any emitter may nest one medium (Mitsuba's `medium` child: the medium it sits in).
std::shared_ptr<Object> make_emitter(const Properties& props, const LoadContext& ctx) {
    const auto media = props.objects(ObjectKind::Medium);
    if (media.size() > 1) throw LoadError(media[1]->location, props.plugin() + ": more than one medium given");
    std::shared_ptr<Emitter> emitter = make_emitter_of_type(props, ctx);
    if (!media.empty()) emitter->medium = std::static_pointer_cast<Medium>(media[0]);
    return emitter;
}

} // namespace penumbra
