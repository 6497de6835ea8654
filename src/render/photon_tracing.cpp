#include "render/photon_tracing.h"

#include "core/interrupt.h"
#include "render/bdpt_subpaths.h"
#include "render/light_medium.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <limits>

namespace penumbra {

namespace {

// The light walk's settings and bounds, and photon path i's random numbers (seed, i, pass).
struct PhotonWalk {
    PhotonWalk(const Scene& scene, const PhotonTracingSettings& settings) : has_media(scene_has_media(scene)) {
        walk.rr_depth = settings.rr_depth;
        max_vertices =
            settings.max_depth < 0 ? std::numeric_limits<size_t>::max() : size_t(settings.max_depth);
        // Infinite lights emit from a disk of the scene's bounding sphere, enlarged as bdpt does.
        bounds = scene.bounding_sphere();
        bounds.radius = std::max(RayEpsilon, bounds.radius * (1.f + RayEpsilon));
    }
    void trace(const Scene& scene, Sampler& sampler, RayCounter& rays, uint64_t seed, uint64_t pass, uint64_t i,
               std::vector<PathVertex>& path) const {
        BDPTContext ctx{scene, walk, sampler, rays, has_media, false, bounds, nullptr};
        sampler.start(seed ^ 0x5851f42d4c957f2dULL, i, pass);
        light_subpath(ctx, path, max_vertices);
    }
    bool has_media;
    BDPTSettings walk;
    size_t max_vertices = 0;
    BoundingSphere bounds;
};

} // namespace

void trace_photon_path(const Scene& scene, const PhotonTracingSettings& settings, uint64_t seed, uint64_t pass,
                       uint32_t index, std::vector<PathVertex>& path, RayCounter& rays) {
    Sampler sampler;
    PhotonWalk(scene, settings).trace(scene, sampler, rays, seed, pass, index, path);
}

PhotonSet trace_photons(const Scene& scene, const PhotonTracingSettings& settings, uint64_t seed, uint64_t pass,
                        PhotonTracingStats& stats) {
    if (settings.paths == 0 || scene.emitters.empty()) return {};
    const uint64_t granularity =
        settings.granularity > 0 ? settings.granularity : std::max<uint64_t>(1024, settings.paths / 256);
    const uint64_t n_units = (settings.paths + granularity - 1) / granularity;
    const PhotonWalk photon_walk(scene, settings);

    std::vector<PhotonSet> units(n_units);
    std::atomic<uint64_t> rays{0};
    tbb::task_arena arena(settings.threads > 0 ? settings.threads : tbb::this_task_arena::max_concurrency());
    arena.execute([&] {
        tbb::parallel_for(uint64_t(0), n_units, [&](uint64_t u) {
            Sampler sampler;
            RayCounter counter;
            std::vector<PathVertex> path;
            const uint64_t end = std::min(settings.paths, (u + 1) * granularity);
            for (uint64_t i = u * granularity; i < end; ++i) {
                if ((i & 1023) == 0) check_interrupt();
                photon_walk.trace(scene, sampler, counter, seed, pass, i, path);
                for (size_t j = 1; j < path.size(); ++j) {
                    const PathVertex& v = path[j];
                    const Photon photon{v.p, v.n, v.wi, v.beta, uint32_t(i), uint16_t(j)};
                    if (v.type == VertexType::Medium) {
                        units[u].volume.push_back(photon);
                        continue;
                    }
                    if (v.type != VertexType::Surface) continue;
                    const BSDF* bsdf = v.si.bsdf();
                    if (!bsdf || !bsdf->has(BSDFSmooth)) continue;
                    units[u].surface.push_back(photon);
                }
            }
            rays += counter.rays;
        });
    });

    PhotonSet photons;
    for (const PhotonSet& unit : units) {
        photons.surface.insert(photons.surface.end(), unit.surface.begin(), unit.surface.end());
        photons.volume.insert(photons.volume.end(), unit.volume.begin(), unit.volume.end());
    }
    stats.rays += rays;
    return photons;
}

} // namespace penumbra
