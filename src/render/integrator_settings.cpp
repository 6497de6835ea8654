#include "render/integrator_settings.h"

namespace penumbra {

namespace {
bool integrator_is(const Scene& scene, const char* plugin) {
    return scene.integrator && scene.integrator->plugin == plugin;
}
} // namespace

PathSettings path_settings(const Scene& scene) {
    if (integrator_is(scene, "path") || integrator_is(scene, "volpath") || integrator_is(scene, "volpathmis"))
        return scene.integrator->path;
    if (scene_integrator_is_bdpt(scene)) {
        const BDPTSettings& b = scene.integrator->bdpt;
        return PathSettings{b.max_depth, b.rr_depth, b.hide_emitters};
    }
    return PathSettings{};
}

BDPTSettings bdpt_settings(const Scene& scene, const PathSettings& path) {
    if (scene_integrator_is_bdpt(scene)) {
        BDPTSettings s = scene.integrator->bdpt;
        s.strategy_s = s.strategy_t = -1;
        return s;
    }
    BDPTSettings s;
    s.max_depth = path.max_depth;
    s.rr_depth = path.rr_depth;
    s.hide_emitters = path.hide_emitters;
    return s;
}

bool scene_integrator_is_bdpt(const Scene& scene) { return integrator_is(scene, "bdpt"); }

const SPPMSettings* sppm_settings(const Scene& scene) {
    return integrator_is(scene, "sppm") ? &scene.integrator->sppm : nullptr;
}

} // namespace penumbra
