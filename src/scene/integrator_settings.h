// The scene's <integrator> as plain data: its plugin type (Object::plugin), its location and its parsed,
// validated settings. render/integrator_factory.cpp makes the integrator object from it; the derivative
// estimators read it. Each integrator's parameter table is at the top of its file in src/render/.
#pragma once
#include "scene/object.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace penumbra {

// `path`, `volpath`, `volpathmis`, `ptracer`.
struct PathSettings {
    int max_depth = -1; // -1: infinite; 1: directly visible emitters only
    int rr_depth = 5;
    bool hide_emitters = false;
};

enum class MISHeuristic { Power, Balance };

// `bdpt`.
struct BDPTSettings {
    int max_depth = -1; // longest path in segments (-1: infinite)
    int rr_depth = 5;
    bool hide_emitters = false;
    MISHeuristic heuristic = MISHeuristic::Power;
    int strategy_s = -1, strategy_t = -1; // >= 0: only this strategy, unweighted (a view of one technique)
};

// Density-estimation kernels of photon mapping (render/photon_kernel.h).
enum class PhotonKernel { Constant, Smooth };

// `sppm`, which the differentiable photon-mapping estimators (diff/dpm/dpm.h) also read.
struct SPPMSettings {
    int64_t photon_count = 250000;
    float initial_radius = 0.f; // 0: automatic (sppm_radius)
    float alpha = 0.7f;
    int max_depth = -1, rr_depth = 5;
    int64_t granularity = 0, max_passes = -1;
    PhotonKernel kernel = PhotonKernel::Constant;
};

// `direct`.
struct DirectSettings {
    int emitter_samples = 1, bsdf_samples = 1;
    bool hide_emitters = false;
};

// `aov`: one output variable, `name:type` in its `aovs` list.
enum class AOVType { Depth, Position, UV, GeoNormal, ShNormal, Albedo, PrimIndex, ShapeIndex };
struct AOV {
    std::string name;
    AOVType type;
};

class Scene;
struct IntegratorSettings;

// An integrator nested in `aov` or `moment`, with its name (`name` attribute, or `_arg_<i>`).
struct NestedIntegrator {
    std::string name;
    std::shared_ptr<const IntegratorSettings> settings;
};

// One <integrator>: the settings of its plugin are filled, the others keep their defaults.
struct IntegratorSettings final : public Object {
    ObjectKind kind() const override { return ObjectKind::Integrator; }
    PathSettings path;     // path, volpath, volpathmis, ptracer
    BDPTSettings bdpt;     // bdpt
    SPPMSettings sppm;     // sppm
    DirectSettings direct; // direct
    std::vector<AOV> aovs; // aov
    // aov: at most one; moment: one or more, all camera-driven.
    std::vector<NestedIntegrator> nested;
};

// Whether the plugin renders by camera ray (render's SamplingIntegrator): path, volpath, volpathmis, direct,
// aov, moment.
bool camera_driven(const std::string& plugin);

// What the derivative estimators follow of the scene's integrator:
// the path settings of its `path`, `volpath`, `volpathmis` or `bdpt` integrator (defaults otherwise);
PathSettings path_settings(const Scene& scene);
// the bdpt integrator's settings (strategy views off), or `path`'s for other integrators (power heuristic);
BDPTSettings bdpt_settings(const Scene& scene, const PathSettings& path);
// whether it is `bdpt`;
bool scene_integrator_is_bdpt(const Scene& scene);
// its `sppm` settings, or null when it is another.
const SPPMSettings* sppm_settings(const Scene& scene);

} // namespace penumbra
