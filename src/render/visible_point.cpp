#include "render/visible_point.h"

#include "render/medium_sampling.h"
#include "render/null_walk.h"
#include "render/volume_visibility.h"

#include <algorithm>
#include <limits>
#include <tuple>

namespace penumbra {

VisiblePoint trace_visible_point(const Scene& scene, Sampler& sampler, Ray ray, Color3f beta,
                                 const EyeSubpathSettings& settings, Color3f& emission, RayCounter& rays,
                                 std::vector<SpecularVertex>* chain) {
    if (chain) chain->clear();
    const BSDFContext ctx{TransportMode::Radiance};
    const int max_depth = settings.max_depth < 0 ? std::numeric_limits<int>::max() : settings.max_depth;
    float eta = 1.f;
    const Medium* medium = sensor_medium(scene);
    // `bounces` bounds the specular chain as the null walk bounds its crossings.
    for (int depth = 1, bounces = 0; depth <= max_depth && bounces < MaxNullCrossings; ++bounces) {
        // To the next event through pure null surfaces, with free flights in the media on the way: a
        // scattering event is the visible point.
        SurfaceInteraction3f si;
        bool absorbed = false, scattered = false;
        Vec3f scatter_p;
        const NullWalk w =
            walk_null_surfaces<NullWalkRule{}>(scene, ray, medium, rays, nullptr, si,
                                               [&](const Medium* m, const Ray& r, float end, FlightRecord*) {
                                                   if (!m) return true;
                                                   const FreeFlightSample ff =
                                                       sample_free_flight(*m, r.o, r.d, end, sampler);
                                                   absorbed = ff.event == FreeFlightSample::Event::Absorbed;
                                                   if (absorbed) return false;
                                                   beta *= ff.weight;
                                                   scattered = ff.event == FreeFlightSample::Event::Scattered;
                                                   scatter_p = ff.p;
                                                   return !scattered;
                                               });
        if (absorbed || w.end == NullWalk::End::Exhausted) return {};
        medium = w.medium;
        ray = w.ray;
        if (scattered) {
            if (depth + 1 > max_depth) return {};
            const Color3f sigma_s = medium->sigma_t(scatter_p) * medium->albedo(scatter_p);
            VisiblePoint vp;
            vp.beta = Color3f(sigma_s.x > 0.f ? beta.x / sigma_s.x : 0.f,
                              sigma_s.y > 0.f ? beta.y / sigma_s.y : 0.f,
                              sigma_s.z > 0.f ? beta.z / sigma_s.z : 0.f);
            vp.depth = depth;
            vp.medium = medium;
            vp.p = scatter_p;
            vp.wi = -ray.d;
            return vp;
        }
        if (!si.is_valid()) {
            emission += beta * scene.eval_environment(ray.d);
            return {};
        }
        if (const Emitter* emitter = si.emitter()) emission += beta * emitter->eval(si);
        const BSDF* bsdf = si.bsdf();
        if (!bsdf) return {};
        const bool smooth = bsdf->has(BSDFSmooth), mixed = smooth && bsdf->has(BSDFDelta);
        if (mixed) beta *= 2.f;
        if (smooth && (!mixed || sampler.next_1d() < 0.5f)) {
            if (depth + 1 > max_depth) return {}; // no photon fits
            VisiblePoint vp;
            vp.si = si;
            vp.beta = beta;
            vp.depth = depth;
            return vp;
        }
        const float u1 = sampler.next_1d();
        const auto [bs, weight] = bsdf->sample(ctx, si, u1, sampler.next_2d());
        if (is_black(weight) || !(bs.sampled_type & BSDFDelta)) return {};
        beta *= weight;
        eta *= bs.eta;
        ray = si.spawn_ray(si.to_world(bs.wo));
        medium = target_medium(*si.shape, si.n, ray.d, medium);
        if (bs.sampled_type == BSDFNull) continue;
        if (chain) chain->push_back({si, bs.eta});
        ++depth;
        // Russian roulette along long specular chains (Mitsuba 3's survival probability).
        if (depth > settings.rr_depth) {
            const float q = std::min(max_component(beta) * eta * eta, 0.95f);
            if (sampler.next_1d() >= q) return {};
            beta /= q;
        }
    }
    return {};
}

PixelVisiblePoint trace_pixel_visible_point(const Scene& scene, Sampler& sampler, int x, int y, uint64_t seed,
                                            uint64_t pass, const EyeSubpathSettings& settings,
                                            RayCounter& rays, std::vector<SpecularVertex>* chain) {
    const Sensor& sensor = *scene.sensor;
    const Film& film = *sensor.film;
    sampler.start(seed, uint64_t(y) * uint64_t(film.width) + uint64_t(x), pass);
    PixelVisiblePoint out;
    out.film = film.sample_position(x, y, sampler.next_2d());
    Color3f weight;
    std::tie(out.ray, weight) = sensor.sample_ray(out.film, sampler.next_2d());
    out.emission = Color3f(0.f);
    out.vp = trace_visible_point(scene, sampler, out.ray, weight, settings, out.emission, rays, chain);
    return out;
}

} // namespace penumbra
