#include "diff/media_radiance.h"

#include "diff/media_walk.h"

namespace penumbra {

Color3f vertex_radiance(const Scene& scene, const RadianceVertex& start, int max_depth, bool emission,
                        const PathSettings& settings, Sampler& sampler, RayCounter& rays) {
    const BSDFContext ctx{TransportMode::Radiance};
    const unsigned max_vertices = unsigned(max_depth); // -1 wraps to "unbounded"
    Color3f L(0.f), beta(1.f);
    RadianceVertex v = start;
    if (emission && v.si.is_valid() && v.si.emitter()) L += v.si.emitter()->eval(v.si);
    if (scene.emitters.empty()) return L;
    for (unsigned depth = 0; depth + 1 < max_vertices; ++depth) {
        const bool surface = v.si.is_valid();
        const BSDF* bsdf = surface ? v.si.bsdf() : nullptr;
        if (surface && !bsdf) break;
        Interaction3f ref;
        ref.p = v.si.p;
        ref.n = surface ? v.si.n : Vec3f(0.f);
        // Next-event estimation: f (BSDF cosine or phase function) L_e Tr / p.
        const auto [ds, em_weight] = scene.sample_emitter_direction(ref, sampler.next_2d(), false);
        if (!is_black(em_weight)) {
            const Color3f f = surface ? bsdf->eval(ctx, v.si, v.si.to_local(ds.d))
                                      : Color3f(v.medium->phase->eval<float>(v.to_viewer, ds.d));
            if (!is_black(f)) {
                const Medium* medium =
                    surface ? target_medium(*v.si.shape, v.si.n, ds.d, v.medium) : v.medium;
                const Ray shadow = std::isinf(ds.dist) ? ref.spawn_ray(ds.d) : ref.spawn_ray_to(ds.p);
                L += beta * f * em_weight * walk_transmittance(scene, shadow, medium, sampler, rays);
            }
        }
        // The next vertex: BSDF or phase sampling (weight 1), then a free flight.
        Vec3f d;
        Ray ray;
        const Medium* medium = v.medium;
        if (surface) {
            const float u1 = sampler.next_1d();
            const auto [bs, weight] = bsdf->sample(ctx, v.si, u1, sampler.next_2d());
            if (is_black(weight)) break;
            d = v.si.to_world(bs.wo);
            beta *= weight;
            medium = target_medium(*v.si.shape, v.si.n, d, medium);
            ray = v.si.spawn_ray(d);
        } else {
            const auto [wo, pdf] = v.medium->phase->sample(v.to_viewer, sampler.next_2d());
            if (!(pdf > 0.f)) break;
            d = wo;
            ray = Ray(v.si.p, d);
        }
        const FlightEnd end = sample_interaction(scene, ray, medium, true, sampler, rays);
        if (end.kind == FlightEnd::Kind::None || end.kind == FlightEnd::Kind::Escaped) break;
        beta *= end.weight;
        v.si = end.kind == FlightEnd::Kind::Surface ? end.si : SurfaceInteraction3f{};
        v.si.p = end.p;
        v.to_viewer = d * -1.f;
        v.medium = end.medium;
        if (int(depth) + 1 >= settings.rr_depth) {
            const float q = std::min(max_component(beta), 0.95f);
            if (sampler.next_1d() >= q) break;
            beta /= q;
        }
    }
    return L;
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
