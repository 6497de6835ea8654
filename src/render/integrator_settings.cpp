#include "render/integrator_settings.h"

#include "render/bdpt.h"
#include "render/path.h"
#include "render/volpath.h"

namespace penumbra {

PathSettings path_settings(const Scene& scene) {
    if (const auto* path = dynamic_cast<const PathIntegrator*>(scene.integrator.get())) return path->settings();
    if (const auto* volpath = dynamic_cast<const VolPathIntegrator*>(scene.integrator.get())) return volpath->settings();
    if (const auto* bdpt = dynamic_cast<const BidirectionalPathTracer*>(scene.integrator.get())) {
        const BDPTSettings& b = bdpt->settings();
        return PathSettings{b.max_depth, b.rr_depth, b.hide_emitters};
    }
    return PathSettings{};
}

BDPTSettings bdpt_settings(const Scene& scene, const PathSettings& path) {
    if (const auto* bdpt = dynamic_cast<const BidirectionalPathTracer*>(scene.integrator.get())) {
        BDPTSettings s = bdpt->settings();
        s.strategy_s = s.strategy_t = -1;
        return s;
    }
    BDPTSettings s;
    s.max_depth = path.max_depth;
    s.rr_depth = path.rr_depth;
    s.hide_emitters = path.hide_emitters;
    return s;
}

bool scene_integrator_is_bdpt(const Scene& scene) {
    return dynamic_cast<const BidirectionalPathTracer*>(scene.integrator.get()) != nullptr;
}

const SPPMSettings* sppm_settings(const Scene& scene) {
    const auto* sppm = dynamic_cast<const SPPMIntegrator*>(scene.integrator.get());
    return sppm ? &sppm->settings() : nullptr;
}

} // namespace penumbra
