#include "diff/media_walk.h"

#include "render/medium_sampling.h"
#include "render/volume_visibility.h"

namespace penumbra {

namespace {

// A bound on the surfaces crossed, against rays stuck on coincident surfaces.
constexpr int MaxCrossings = 256;

bool is_null(const SurfaceInteraction3f& si) { return si.bsdf() && si.bsdf()->flags() == BSDFNull; }

} // namespace

FlightEnd sample_interaction(const Scene& scene, Ray ray, const Medium* medium, bool volume_vertices,
                             Sampler& sampler, RayCounter& rays) {
    FlightEnd out;
    Color3f weight(1.f);
    for (int crossing = 0; crossing < MaxCrossings; ++crossing) {
        ++rays.rays;
        const SurfaceInteraction3f si = scene.intersect(ray);
        const float end = si.is_valid() ? si.t : Infinity;
        if (medium && volume_vertices) {
            const FreeFlightSample ff = sample_free_flight(*medium, ray.o, ray.d, end, sampler);
            weight *= ff.weight;
            if (ff.event == FreeFlightSample::Event::Absorbed || is_black(weight)) return out;
            if (ff.event == FreeFlightSample::Event::Scattered) {
                out.kind = FlightEnd::Kind::Medium;
                out.p = ff.p;
                out.medium = medium;
                out.weight = weight;
                return out;
            }
        } else if (medium) {
            weight *= transmittance(*medium, ray.o, ray.d, end, sampler);
            if (is_black(weight)) return out;
        }
        if (!si.is_valid()) {
            out.kind = FlightEnd::Kind::Escaped;
            out.medium = medium;
            out.weight = weight;
            return out;
        }
        if (is_null(si)) {
            medium = target_medium(*si.shape, si.n, ray.d, medium);
            ray = Ray(si.spawn_ray(ray.d).o, ray.d);
            continue;
        }
        out.kind = FlightEnd::Kind::Surface;
        out.si = si;
        out.p = si.p;
        out.medium = medium;
        out.weight = weight;
        return out;
    }
    return out;
}

SurfaceInteraction3f first_opaque_hit(const Scene& scene, Ray ray, RayCounter& rays) {
    const Vec3f origin = ray.o;
    for (int crossing = 0; crossing < MaxCrossings; ++crossing) {
        ++rays.rays;
        SurfaceInteraction3f si = scene.intersect(ray);
        if (!si.is_valid()) return si;
        if (!is_null(si)) {
            si.t = norm(si.p - origin);
            return si;
        }
        ray = ray_beyond(ray, si);
        if (!(ray.tmax > 0.f)) return SurfaceInteraction3f{};
    }
    return SurfaceInteraction3f{};
}

} // namespace penumbra
