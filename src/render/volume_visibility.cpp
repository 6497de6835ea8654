#include "render/volume_visibility.h"

#include "render/medium_sampling.h"
#include "render/null_walk.h"

namespace penumbra {

Color3f segment_transmittance(const Scene& scene, Ray ray, const Medium* medium, Sampler& sampler,
                              RayCounter& rays, const Medium** end_medium, LegChain* pieces) {
    Color3f tr(1.f);
    SurfaceInteraction3f hit;
    const NullWalk w = walk_null_surfaces<NullWalkRule{.bounded = true}>(
        scene, ray, medium, rays, pieces, hit,
        [&](const Medium* m, const Ray& r, float end, FlightRecord* record) {
            if (m) tr *= transmittance(*m, r.o, r.d, end, sampler, record);
            return !is_black(tr);
        });
    if (end_medium) *end_medium = w.medium;
    const bool blocked = w.end == NullWalk::End::Surface || w.end == NullWalk::End::Exhausted;
    return blocked ? Color3f(0.f) : tr;
}

} // namespace penumbra
