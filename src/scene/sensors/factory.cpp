// Sensor factory, and the parameters shared by all projective cameras (Mitsuba's Sensor and ProjectiveCamera
// bases):
//   to_world                     transform  identity
//   near_clip, far_clip          float      0.01, 10000
//   focus_distance               float      far_clip   (thinlens; the other sensors ignore it)
//   shutter_open, shutter_close  float      0, 0       (accepted; penumbra renders static scenes)
//   film                         nested     hdrfilm with its defaults
//   sampler                      nested     independent with its defaults
//   medium                       nested     none: the medium the sensor sits in
#include "scene/sensors/sensor_common.h"

#include "scene/medium.h"

namespace penumbra {

namespace {

// The single nested object of a kind, or nullptr; a second one is an error at its own location.
std::shared_ptr<Object> single_child(const Properties& props, ObjectKind kind) {
    const auto children = props.objects(kind);
    if (children.size() > 1)
        throw LoadError(children[1]->location,
                        props.plugin() + ": more than one " + kind_name(kind) + " given");
    return children.empty() ? nullptr : children[0];
}

} // namespace

void load_sensor_common(Sensor& sensor, const Properties& props, const LoadContext& ctx) {
    sensor.to_world = props.get_transform("to_world");
    sensor.near_clip = props.get_float("near_clip", 1e-2f);
    sensor.far_clip = props.get_float("far_clip", 1e4f);
    if (!(sensor.near_clip > 0.f)) props.raise("near_clip", "near_clip must be greater than zero");
    if (!(sensor.near_clip < sensor.far_clip))
        props.raise("far_clip", "near_clip must be smaller than far_clip");
    props.get_float("focus_distance", sensor.far_clip);
    const float open = props.get_float("shutter_open", 0.f), close = props.get_float("shutter_close", 0.f);
    if (close < open) props.raise("shutter_close", "shutter_close must not be smaller than shutter_open");

    std::shared_ptr<Object> film = single_child(props, ObjectKind::Film);
    if (!film) {
        film = make_film(Properties("hdrfilm", props.location()), ctx);
        film->plugin = "hdrfilm";
        film->location = props.location();
    }
    sensor.film = std::static_pointer_cast<Film>(film);

    std::shared_ptr<Object> sampler = single_child(props, ObjectKind::Sampler);
    if (!sampler) {
        sampler = make_sampler(Properties("independent", props.location()), ctx);
        sampler->plugin = "independent";
        sampler->location = props.location();
    }
    sensor.medium = std::dynamic_pointer_cast<Medium>(single_child(props, ObjectKind::Medium));
    sensor.sampler = std::dynamic_pointer_cast<SamplerDesc>(sampler);
    if (!sensor.sampler) throw LoadError(sampler->location, props.plugin() + ": unsupported sampler object");
}

std::shared_ptr<Object> make_sensor(const Properties& props, const LoadContext& ctx) {
    const std::string& type = props.plugin();
    if (type == "perspective") return make_perspective_sensor(props, ctx);
    if (type == "orthographic") return make_orthographic_sensor(props, ctx);
    if (type == "thinlens") return make_thinlens_sensor(props, ctx);
    if (type == "radiancemeter") return make_radiancemeter_sensor(props, ctx);
    if (type == "irradiancemeter") return make_irradiancemeter_sensor(props, ctx);
    throw_unsupported_plugin(props, ObjectKind::Sensor);
}

} // namespace penumbra
