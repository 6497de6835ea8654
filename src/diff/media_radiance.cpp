#include "diff/media_radiance.h"

#include "diff/media_walk.h"
#include "render/volpath_tracer.h"

namespace penumbra {

Color3f vertex_radiance(const Scene& scene, const RadianceVertex& start, int max_depth, bool emission,
                        const PathSettings& settings, Sampler& sampler, RayCounter& rays) {
    Color3f L(0.f);
    const bool surface = start.si.is_valid();
    if (emission && surface && start.si.emitter()) L += start.si.emitter()->eval(start.si);
    // The rest of the path: render/volpath_tracer.h on the reference geometry, its own hero channel drawn
    // here (the flights that reached the vertex were weighted by the caller).
    VolVertex<float> v;
    v.surface = surface;
    v.hit = start.si;
    v.p0 = v.p = start.si.p;
    v.wi0 = start.to_viewer;
    v.medium = start.medium;
    const Vec3f prev = start.si.p + start.to_viewer;
    const SpectralFlights flights{SpectralMIS::PerPath, sample_hero_channel(sampler)};
    PathSettings rest = settings;
    rest.max_depth = max_depth;
    return L + trace_volpath_from<float>(scene, sampler, v, prev, flights, ReferenceGeometry{}, rest, rays);
}

ArrivingRadiance arriving_radiance(const Scene& scene, const Ray& ray, const Medium* medium,
                                   const PathSettings& settings, Sampler& sampler, RayCounter& rays) {
    ArrivingRadiance out;
    out.end = sample_interaction(scene, ray, medium, true, sampler, rays);
    const bool emission = !settings.hide_emitters;
    switch (out.end.kind) {
    case FlightEnd::Kind::None: return out;
    case FlightEnd::Kind::Escaped:
        if (emission && settings.max_depth != 0) out.radiance = scene.eval_environment(ray.d);
        break;
    case FlightEnd::Kind::Medium: {
        RadianceVertex v{SurfaceInteraction3f{}, ray.d * -1.f, out.end.medium};
        v.si.p = out.end.p;
        out.radiance = vertex_radiance(scene, v, settings.max_depth, false, settings, sampler, rays);
        break;
    }
    case FlightEnd::Kind::Surface:
        out.radiance = vertex_radiance(scene, {out.end.si, ray.d * -1.f, out.end.medium}, settings.max_depth, emission,
                                       settings, sampler, rays);
        break;
    }
    out.radiance *= out.end.weight;
    return out;
}

} // namespace penumbra
