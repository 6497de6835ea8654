// The photon pass of photon mapping: light subpaths traced from the scene's emitters (every kind: area,
// point, spot, projector, directional, environment) by bidirectional path tracing's light walk
// (render/bdpt_subpaths.h), each surface vertex with a non-delta BSDF kept as a photon.
#pragma once
#include "render/integrator.h"
#include "render/path_vertex.h"
#include "render/photon_map.h"
#include "scene/scene.h"

#include <cstdint>
#include <vector>

namespace penumbra {

struct PhotonTracingSettings {
    uint64_t paths = 0;       // light subpaths traced in the pass
    int max_depth = -1;       // photons of at most max_depth - 1 segments (-1: unlimited; eye paths add >= 1)
    int rr_depth = 5;         // light-subpath depth at which Russian roulette starts
    uint64_t granularity = 0; // light subpaths per work unit (0: automatic); does not change the photons
    int threads = 0;          // 0: all hardware threads
};

struct PhotonTracingStats {
    uint64_t rays = 0;
};

// The photons of pass `pass`: light subpath i draws its numbers from the stream (seed, i, pass), and the
// photons are listed by subpath index, then depth, so they are the same whatever the thread count. Light
// subpaths cross participating media (free flights, phase-function scattering) when the scene has any.
PhotonSet trace_photons(const Scene& scene, const PhotonTracingSettings& settings, uint64_t seed, uint64_t pass,
                        PhotonTracingStats& stats);

// Light subpath `index` of pass `pass` again, vertex for vertex as trace_photons() traced it (its photons are
// path[photon.depth]): the differentiable estimators re-trace the few paths they differentiate.
void trace_photon_path(const Scene& scene, const PhotonTracingSettings& settings, uint64_t seed, uint64_t pass,
                       uint32_t index, std::vector<PathVertex>& path, RayCounter& rays);

} // namespace penumbra
