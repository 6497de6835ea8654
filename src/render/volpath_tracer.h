// Unidirectional volumetric path tracing (Mitsuba 3's `volpath` and `volpathmis`): the radiative transfer
// equation sampled from the camera, with free-flight sampling in media (render/medium_sampling.h), next-event
// estimation at surface and medium vertices through media and index-matched (null) boundaries
// (segment_transmittance), and MIS with the power heuristic (Veach 1997, Eq. 9.13) between emitter sampling
// and BSDF / phase-function sampling, as render/path_tracer.h does for surfaces.
//
// MIS uses the solid-angle densities of the direction only: both strategies see the same transmittance (NEE
// estimates it, BSDF/phase sampling reaches the emitter with the free-flight pass weights), so the weights of
// the two strategies sum to one for every path and the estimator stays unbiased.
//
// Depth (Mitsuba): the number of scattering vertices (surface or medium); crossing a null lobe is not one. A
// path with k scattering vertices is counted if k < max_depth. Russian roulette as path_tracer.h.
//
// Spectral MIS: `PerSegment` (volpath) draws each free flight with the per-segment channel balance of
// sample_free_flight; `PerPath` (volpathmis) draws a hero channel once per path and weights the whole path by
// the balance heuristic over channels (render/hero_free_flight.h). Surface and phase sampling do not depend
// on the channel, so both are unbiased; whole-path MIS bounds the weight of a path by 3 where per-segment MIS
// can give 3^k for k segments in a strongly chromatic medium.
//
// The estimator is written on the scalar type T of the accumulated radiance (T = float renders); sampling and
// the densities of MIS and Russian roulette are float.
#pragma once
#include "render/emitter_hit.h"
#include "render/hero_free_flight.h"
#include "render/integrator.h"
#include "render/medium_sampling.h"
#include "render/mis.h"
#include "render/path_tracer.h"
#include "render/volume_visibility.h"
#include "scene/shape.h"

#include <algorithm>

namespace penumbra {

enum class SpectralMIS { PerSegment, PerPath };

namespace volpath_detail {

inline float mean(const Color3f& c) { return (c.x + c.y + c.z) / 3.f; }

// The path state shared by surface and medium vertices.
template <typename T> struct PathState {
    Color3<T> L{T(0)};
    Color3<T> beta{T(1)}; // f/p of the sampled path (hero-channel density for PerPath)
    Color3f ratio{1.f};   // PerPath: densities of the other channels over the hero's (PerSegment: 1)
    float eta = 1.f;
    unsigned depth = 0; // scattering vertices so far
    // The last scattering vertex (or the camera), for the MIS weight of emission found by sampling.
    Interaction3f last;
    float last_pdf = 1.f;
    bool last_unweighted =
        true;              // emission found next has weight 1 (camera, delta lobe, no NEE at the vertex)
    float travelled = 0.f; // distance from the last scattering vertex along the current direction

    // beta / mean(ratio): the path's estimate factor.
    Color3<T> weight() const { return beta / T(mean(ratio)); }
    void add(const Color3f& value) { L += weight() * Color3<T>(value); }
};

// Next-event estimation from `ref` (a surface point or a point in a medium): the emitter sample, its
// transmittance through media and null boundaries starting in `medium`, and f (bsdf cosine or phase function)
// with its density for the MIS weight. Returns f L_e Tr w / p.
template <typename Eval>
Color3f next_event(const Scene& scene, const Interaction3f& ref, const SurfaceInteraction3f* surface,
                   const Medium* medium, Sampler& sampler, RayCounter& rays, Eval&& eval) {
    const auto [ds, em_weight] = scene.sample_emitter_direction(ref, sampler.next_2d(), false);
    if (is_black(em_weight)) return Color3f(0.f);
    const auto [f, pdf] = eval(ds.d);
    if (is_black(f)) return Color3f(0.f);
    const Ray shadow = std::isinf(ds.dist) ? ref.spawn_ray(ds.d) : ref.spawn_ray_to(ds.p);
    const Medium* shadow_medium = surface ? target_medium(*surface->shape, surface->n, ds.d, medium) : medium;
    const Color3f tr = segment_transmittance(scene, shadow, shadow_medium, sampler, rays); // counts its rays
    if (is_black(tr)) return Color3f(0.f);
    const float w = ds.delta ? 1.f : mis_power(ds.pdf, pdf);
    return f * em_weight * tr * w;
}

// Russian roulette after a scattering vertex (path_tracer.h's rule on the path's estimate factor).
template <typename T>
bool survives_roulette(PathState<T>& s, const PathSettings& settings, Sampler& sampler) {
    if (s.depth < unsigned(settings.rr_depth)) return true;
    const Color3<T> w = s.weight();
    const Color3f wf(detach(w.x), detach(w.y), detach(w.z));
    const float q = std::min(max_component(wf) * s.eta * s.eta, 0.95f);
    if (sampler.next_1d() >= q) return false;
    s.beta /= T(q);
    return true;
}

} // namespace volpath_detail

// Radiance arriving at the sensor along `primary`, estimated along one sampled path.
template <typename T>
Color3<T> trace_volpath(const Scene& scene, Sampler& sampler, const Ray& primary,
                        const PathSettings& settings, SpectralMIS spectral, RayCounter& rays) {
    using namespace volpath_detail;
    const BSDFContext ctx{TransportMode::Radiance};
    PathState<T> s;
    if (settings.max_depth == 0) return s.L;
    const unsigned max_depth = unsigned(settings.max_depth); // -1 wraps to "infinite"
    int hero = -1; // PerPath: drawn at the first free flight (paths in vacuum consume path's sample stream)
    const bool nee = !scene.emitters.empty();

    const Medium* medium = sensor_medium(scene);
    Ray ray = primary;
    s.last.p = ray.o;

    for (;;) {
        const SurfaceInteraction3f si = scene.intersect(ray);

        // Free flight through the current medium up to the surface (or to infinity).
        if (medium) {
            const float tmax = si.is_valid() ? si.t : Infinity;
            Vec3f p;
            bool scattered;
            if (spectral == SpectralMIS::PerPath) {
                if (hero < 0) hero = std::min(int(sampler.next_1d() * 3.f), 2);
                const HeroFreeFlight ff = sample_free_flight_hero(*medium, ray.o, ray.d, tmax, hero, sampler);
                s.beta *= Color3<T>(ff.weight);
                s.ratio *= ff.ratio;
                scattered = ff.event == FreeFlightSample::Event::Scattered;
                p = ff.p;
            } else {
                const FreeFlightSample ff = sample_free_flight(*medium, ray.o, ray.d, tmax, sampler);
                s.beta *= Color3<T>(ff.weight);
                scattered = ff.event == FreeFlightSample::Event::Scattered;
                p = ff.p;
            }
            const Color3<T> w = s.weight();
            if (detach(w.x) == 0.f && detach(w.y) == 0.f && detach(w.z) == 0.f) break; // absorbed
            if (scattered) {
                // A medium vertex: NEE with the phase function, then phase sampling (exact: weight 1).
                if (s.depth + 1 >= max_depth) break;
                const PhaseFunction& phase = *medium->phase;
                Interaction3f mi;
                mi.p = p;
                mi.t = 0.f;
                const Vec3f wi = -ray.d;
                if (nee && medium->sample_emitters) {
                    s.add(next_event(scene, mi, nullptr, medium, sampler, rays, [&](const Vec3f& wo) {
                        const float ph = phase.eval<float>(wi, wo);
                        return std::pair{Color3f(ph), ph};
                    }));
                }
                const auto [wo, pdf] = phase.sample(wi, sampler.next_2d());
                if (!(pdf > 0.f)) break;
                s.last = mi;
                s.last_pdf = pdf;
                s.last_unweighted = !medium->sample_emitters;
                s.travelled = 0.f;
                ray = Ray(p, wo);
                ++rays.rays;
                ++s.depth;
                if (!survives_roulette(s, settings, sampler)) break;
                continue;
            }
        }

        // The ray reached a surface or escaped: emission, weighted against emitter sampling from the last
        // scattering vertex (at the distance travelled since, through null boundaries).
        if (!(s.depth == 0 && settings.hide_emitters)) {
            SurfaceInteraction3f seen = si;
            seen.t = s.travelled + si.t;
            for_each_emitter_hit(scene, s.last, ray.d, seen,
                                 [&](const Emitter*, const Color3f& Le, float em_pdf) {
                                     s.add(Le * (s.last_unweighted ? 1.f : mis_power(s.last_pdf, em_pdf)));
                                 });
        }
        if (!si.is_valid()) break;
        const BSDF* bsdf = si.bsdf();
        if (!bsdf) break;

        // Next-event estimation at the surface.
        if (nee && bsdf->has(BSDFSmooth) && s.depth + 1 < max_depth) {
            s.add(next_event(scene, si, &si, medium, sampler, rays, [&](const Vec3f& wo) {
                const Vec3f local = si.to_local(wo);
                return std::pair{bsdf->eval(ctx, si, local), bsdf->pdf(ctx, si, local)};
            }));
        } else {
            sampler.next_2d(); // keep the sample stream aligned across materials
        }

        // BSDF sampling; a null lobe continues the path without a scattering vertex.
        const float u1 = sampler.next_1d();
        const auto [bs, bsdf_weight] = bsdf->sample(ctx, si, u1, sampler.next_2d());
        if (is_black(bsdf_weight)) break;
        const bool null = bs.sampled_type == BSDFNull;
        if (!null && s.depth + 1 >= max_depth) break;
        const Vec3f d = si.to_world(bs.wo);
        s.beta *= Color3<T>(bsdf_weight);
        medium = target_medium(*si.shape, si.n, d, medium);
        ray = si.spawn_ray(d);
        ++rays.rays;
        if (null) {
            // Next-event estimation crosses pure null surfaces only (segment_transmittance): beyond the null
            // lobe of any other BSDF (mask, blends) it saw nothing, so emission found from here on takes
            // weight 1.
            if (bsdf->flags() != BSDFNull) s.last_unweighted = true;
            s.travelled += si.t;
            continue;
        }
        s.last = si;
        s.last_pdf = bs.pdf;
        s.last_unweighted = (bs.sampled_type & BSDFDelta) != 0;
        s.travelled = 0.f;
        s.eta *= bs.eta;
        ++s.depth;
        if (!survives_roulette(s, settings, sampler)) break;
    }
    return s.L;
}

} // namespace penumbra
