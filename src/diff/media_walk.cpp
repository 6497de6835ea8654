#include "diff/media_walk.h"

#include "render/medium_sampling.h"
#include "render/null_walk.h"

namespace penumbra {

FlightEnd sample_interaction(const Scene& scene, Ray ray, const Medium* medium, bool volume_vertices,
                             Sampler& sampler, RayCounter& rays) {
    FlightEnd out;
    Color3f weight(1.f);
    bool scattered = false;
    SurfaceInteraction3f hit;
    const NullWalk w = walk_null_surfaces<NullWalkRule{}>(
        scene, ray, medium, rays, nullptr, hit, [&](const Medium* m, const Ray& r, float end, FlightRecord*) {
            if (!m) return true;
            if (!volume_vertices) {
                weight *= transmittance(*m, r.o, r.d, end, sampler);
                return !is_black(weight);
            }
            const FreeFlightSample ff = sample_free_flight(*m, r.o, r.d, end, sampler);
            weight *= ff.weight;
            if (ff.event == FreeFlightSample::Event::Absorbed || is_black(weight)) return false;
            scattered = ff.event == FreeFlightSample::Event::Scattered;
            if (scattered) out.p = ff.p;
            return !scattered;
        });
    switch (w.end) {
    case NullWalk::End::Stopped:
        if (!scattered) return FlightEnd{}; // absorbed
        out.kind = FlightEnd::Kind::Medium;
        break;
    case NullWalk::End::Escaped:
        out.kind = FlightEnd::Kind::Escaped;
        break;
    case NullWalk::End::Surface:
        out.kind = FlightEnd::Kind::Surface;
        out.si = hit;
        out.p = hit.p;
        break;
    default:
        return FlightEnd{}; // a walk stuck on coincident surfaces
    }
    out.medium = w.medium;
    out.weight = weight;
    return out;
}

SurfaceInteraction3f first_opaque_hit(const Scene& scene, Ray ray, RayCounter& rays) {
    SurfaceInteraction3f hit;
    const NullWalk w = walk_null_surfaces<NullWalkRule{.bounded = true}>(scene, ray, nullptr, rays, nullptr,
                                                                         hit, no_segment_action);
    if (w.end == NullWalk::End::Surface)
        hit.t = norm(hit.p - ray.o);
    else if (w.end != NullWalk::End::Escaped)
        return SurfaceInteraction3f{};
    return hit;
}

} // namespace penumbra
