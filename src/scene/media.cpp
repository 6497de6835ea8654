// Factories for participating media and phase functions (Mitsuba 3 parameters and defaults).
//
// medium "homogeneous":   albedo (float/spectrum, 0.75), sigma_t (float/spectrum, 1), scale (float, 1),
//                         sample_emitters (boolean, true), has_spectral_extinction (boolean, true),
//                         one nested phase (default isotropic)
// phase "isotropic":      no parameters
// phase "hg":             g (float, 0.8), Henyey-Greenstein asymmetry in (-1, 1)
#include "scene/factory.h"
#include "scene/medium.h"

namespace penumbra {

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

// sigma_t is the extinction in inverse scene units, premultiplied by `scale` (Mitsuba: sigma_t * scale).
std::shared_ptr<Object> make_medium(const Properties& props, const LoadContext& ctx) {
    if (props.plugin() != "homogeneous") throw_unsupported_plugin(props, ObjectKind::Medium);
    auto medium = std::make_shared<Medium>();
    medium->albedo = props.get_color("albedo", Color3f(0.75f));
    medium->sigma_t = props.get_color("sigma_t", Color3f(1.f)) * props.get_float("scale", 1.f);
    medium->sample_emitters = props.get_bool("sample_emitters", true);
    // Only changes the estimator's efficiency, not its expectation, in RGB rendering: accepted as a no-op.
    props.get_bool("has_spectral_extinction", true);
    if (min_component(medium->sigma_t) < 0.f)
        props.raise("sigma_t", "the extinction 'sigma_t' must be non-negative");

    const auto phases = props.objects(ObjectKind::Phase);
    if (phases.size() > 1)
        throw LoadError(props.location(), "homogeneous: only one nested phase function is allowed");
    if (phases.empty()) {
        auto iso = make_phase(Properties("isotropic", props.location()), ctx);
        iso->plugin = "isotropic";
        iso->location = props.location();
        medium->phase = std::static_pointer_cast<PhaseFunction>(iso);
    } else {
        medium->phase = std::static_pointer_cast<PhaseFunction>(phases.front());
    }
    return medium;
}

} // namespace penumbra
