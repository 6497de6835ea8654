#include "render/volume_visibility.h"

#include "render/medium_sampling.h"

namespace penumbra {

Ray ray_beyond(const Ray& ray, const SurfaceInteraction3f& si) {
    Ray next = si.spawn_ray(ray.d);
    next.tmax = ray.tmax - si.t - dot(next.o - si.p, ray.d);
    return next;
}

Color3f segment_transmittance(const Scene& scene, Ray ray, const Medium* medium, Sampler& sampler,
                              RayCounter& rays, const Medium** end_medium, LegChain* pieces) {
    Color3f tr(1.f);
    if (pieces) pieces->clear();
    float travelled = 0.f;
    if (end_medium) *end_medium = medium;
    // A bound on the number of null surfaces crossed guards against rays stuck on coincident surfaces.
    for (int crossing = 0; crossing < 256; ++crossing) {
        ++rays.rays;
        const SurfaceInteraction3f si = scene.intersect(ray);
        const float end = si.is_valid() ? si.t : ray.tmax;
        LegPiece* piece = pieces ? &pieces->add(medium, travelled) : nullptr;
        if (piece) piece->bound = si;
        if (medium) {
            tr *= transmittance(*medium, ray.o, ray.d, end, sampler, piece ? &piece->record : nullptr);
            if (is_black(tr)) return tr;
        }
        if (!si.is_valid()) return tr;
        const BSDF* bsdf = si.bsdf();
        if (!bsdf || bsdf->flags() != BSDFNull) return Color3f(0.f);
        medium = target_medium(*si.shape, si.n, ray.d, medium);
        if (end_medium) *end_medium = medium;
        travelled += si.t;
        ray = ray_beyond(ray, si);
        if (!(ray.tmax > 0.f)) return tr;
    }
    return Color3f(0.f);
}

} // namespace penumbra
