// The settings of the scene's integrator that the derivative estimators follow (depth limits, the
// bidirectional tracer's, the photon mapper's), read without knowing which integrator class renders them.
#pragma once
#include "render/bdpt_subpaths.h"
#include "render/path_tracer.h"
#include "render/sppm.h"

namespace penumbra {

// Path settings from the scene's `path`, `volpath` or `bdpt` integrator (defaults otherwise).
PathSettings path_settings(const Scene& scene);
// The bdpt integrator's settings (strategy views off), or `path`'s for other integrators (power heuristic).
BDPTSettings bdpt_settings(const Scene& scene, const PathSettings& path);
// Whether the scene's integrator is `bdpt`.
bool scene_integrator_is_bdpt(const Scene& scene);
// The scene's `sppm` settings, or null when its integrator is another.
const SPPMSettings* sppm_settings(const Scene& scene);

} // namespace penumbra
