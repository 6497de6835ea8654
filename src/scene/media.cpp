// Factories for participating media, phase functions and volumes (Mitsuba 3 parameters and defaults).
//
// medium "homogeneous":   sigma_t (float/spectrum/volume, 1), albedo (float/spectrum/volume, 0.75), or instead
//                         sigma_a and sigma_s (float/spectrum): sigma_t = sigma_a + sigma_s, albedo = sigma_s /
//                         sigma_t; scale (float, 1), sample_emitters (boolean, true), has_spectral_extinction
//                         (boolean, true), one nested phase (default isotropic). sigma_t must be constant.
// phase "isotropic":      no parameters
// phase "hg":             g (float, 0.8), Henyey-Greenstein asymmetry in (-1, 1)
// volume "constvolume":   value (float/spectrum, 1)
// medium "heterogeneous" and volume "gridvolume" (alias "grid"): scene/heterogeneous.cpp,
// scene/volumes/gridvolume.cpp.
#include "scene/media_loading.h"

#include "core/warp.h"

namespace penumbra {

std::pair<Vec3f, float> PhaseFunction::sample(const Vec3f& wi, const Vec2f& u) const {
    // Inverts the HG CDF in cos θ between -wi (the unscattered direction) and wo (Pharr et al., pbrt-v4 §11.3).
    float cos_theta;
    if (std::abs(g) < 1e-3f) {
        cos_theta = 1.f - 2.f * u.x;
    } else {
        const float sq = (1.f - g * g) / (1.f + g - 2.f * g * u.x);
        cos_theta = (1.f + g * g - sq * sq) / (2.f * g);
    }
    cos_theta = std::clamp(cos_theta, -1.f, 1.f);
    const float sin_theta = std::sqrt(std::max(0.f, 1.f - cos_theta * cos_theta));
    const float phi = 2.f * Pi * u.y;
    const Frame3f frame(-wi);
    const Vec3f wo = frame.to_world(Vec3f(sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta));
    return {wo, eval<float>(wi, wo)};
}

void PhaseFunction::traverse(ParamVisitor& v) {
    if (plugin == "hg") v.put("g", &g, 1, &g_index);
}

void HomogeneousMedium::traverse(ParamVisitor& v) {
    v.put_object("sigma_t", sigma_t_volume.get());
    v.put_object("albedo", albedo_volume.get());
    if (phase) v.put_object("phase_function", phase.get());
}

std::shared_ptr<Volume> get_volume(const Properties& props, const std::string& name, const Color3f& def) {
    if (!props.has(name)) return std::make_shared<ConstVolume>(def);
    if (props.type(name) == Properties::Tag::Object) {
        auto volume = std::dynamic_pointer_cast<Volume>(props.get_object(name, ObjectKind::Volume));
        if (!volume) props.raise(name, "'" + name + "' must be a float, a spectrum or a <volume>");
        return volume;
    }
    return std::make_shared<ConstVolume>(props.get_color(name));
}

std::shared_ptr<PhaseFunction> get_phase(const Properties& props, const LoadContext& ctx) {
    const auto phases = props.objects(ObjectKind::Phase);
    if (phases.size() > 1)
        throw LoadError(phases[1]->location, props.plugin() + ": only one nested phase function is allowed");
    if (!phases.empty()) return std::static_pointer_cast<PhaseFunction>(phases.front());
    auto iso = make_phase(Properties("isotropic", props.location()), ctx);
    iso->plugin = "isotropic";
    iso->location = props.location();
    return std::static_pointer_cast<PhaseFunction>(iso);
}

std::shared_ptr<Object> make_phase(const Properties& props, const LoadContext&) {
    auto phase = std::make_shared<PhaseFunction>();
    if (props.plugin() == "hg") {
        phase->g = props.get_float("g", 0.8f);
        if (!(phase->g > -1.f && phase->g < 1.f))
            props.raise("g", "the asymmetry parameter 'g' must lie in (-1, 1)");
    } else if (props.plugin() != "isotropic") {
        throw_unsupported_plugin(props, ObjectKind::Phase);
    }
    return phase;
}

namespace {

std::shared_ptr<Object> make_homogeneous(const Properties& props, const LoadContext& ctx) {
    auto medium = std::make_shared<HomogeneousMedium>();
    const bool by_albedo = props.has("sigma_t") || props.has("albedo");
    const bool by_coefficients = props.has("sigma_a") || props.has("sigma_s");
    if (by_albedo && by_coefficients)
        props.raise(props.has("sigma_a") ? "sigma_a" : "sigma_s",
                    "give either sigma_t and albedo, or sigma_a and sigma_s, not both");
    if (by_coefficients) {
        const Color3f sigma_a = props.get_color("sigma_a", Color3f(0.f)),
                      sigma_s = props.get_color("sigma_s", Color3f(0.f));
        if (min_component(sigma_a) < 0.f) props.raise("sigma_a", "'sigma_a' must be non-negative");
        if (min_component(sigma_s) < 0.f) props.raise("sigma_s", "'sigma_s' must be non-negative");
        const Color3f sigma_t = sigma_a + sigma_s;
        auto ratio = [](float s, float t) { return t > 0.f ? s / t : 0.f; };
        medium->sigma_t_volume = std::make_shared<ConstVolume>(sigma_t);
        medium->albedo_volume = std::make_shared<ConstVolume>(
            Color3f(ratio(sigma_s.x, sigma_t.x), ratio(sigma_s.y, sigma_t.y), ratio(sigma_s.z, sigma_t.z)));
    } else {
        medium->sigma_t_volume = get_volume(props, "sigma_t", Color3f(1.f));
        medium->albedo_volume = get_volume(props, "albedo", Color3f(0.75f));
        if (!medium->sigma_t_volume->is_constant())
            props.raise("sigma_t", "homogeneous: 'sigma_t' must be constant (use a heterogeneous medium for a grid)");
    }
    medium->scale = props.get_float("scale", 1.f);
    if (!(medium->scale >= 0.f) || !std::isfinite(medium->scale))
        props.raise("scale", "'scale' must be finite and non-negative");
    if (min_component(medium->sigma_t_t<float>(Vec3f(0.f))) < 0.f)
        props.raise(props.has("sigma_t") ? "sigma_t" : "sigma_a", "the extinction must be non-negative");
    medium->sample_emitters = props.get_bool("sample_emitters", true);
    // Only changes the estimator's efficiency, not its expectation, in RGB rendering: accepted as a no-op.
    props.get_bool("has_spectral_extinction", true);
    medium->phase = get_phase(props, ctx);
    return medium;
}

} // namespace

std::shared_ptr<Object> make_medium(const Properties& props, const LoadContext& ctx) {
    if (props.plugin() == "homogeneous") return make_homogeneous(props, ctx);
    if (props.plugin() == "heterogeneous") return make_heterogeneous_medium(props, ctx);
    throw_unsupported_plugin(props, ObjectKind::Medium);
}

std::shared_ptr<Object> make_volume(const Properties& props, const LoadContext& ctx) {
    if (props.plugin() == "constvolume") return std::make_shared<ConstVolume>(props.get_color("value", Color3f(1.f)));
    if (props.plugin() == "gridvolume" || props.plugin() == "grid") return make_gridvolume(props, ctx);
    throw_unsupported_plugin(props, ObjectKind::Volume);
}

} // namespace penumbra
