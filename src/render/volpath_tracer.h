// Volumetric path tracing, written once on the scalar type T over a Geometry (paper 001 §4.1, §5.1, §6.2):
// T = float on the reference geometry renders — Mitsuba 3's `volpath` and `volpathmis` (trace_volpath) and
// the radiance the boundary terms need (diff/media_radiance.h) —, T = Var on the moving geometry is the
// interior term of the generalized differential path integral with surface and medium vertices
// (diff/psdr/interior_media.h).
//
// Paths are sampled in the reference configuration with float arithmetic (BSDF and phase sampling, free
// flights, next-event estimation, MIS and Russian roulette are detached). Each step from a vertex x_{i-1} to
// the next vertex x_i (a surface vertex or a medium vertex, reached through index-matched `null` surfaces by
// render/null_walk.h) contributes
//     f(x_{i-2} → x_{i-1} → x_i) / p_σ  ·  Tr σ_s / p_t (free-flight weights, render/flight_record.h)
//     ·  G(x_{i-1}, x_i) J(x_i) / G_0,
// with G = |n_i · ω| / ℓ² for a surface vertex and 1 / ℓ² for a medium vertex (its measure is the volume,
// J = dV(x)/dV(p), Eq. 46). At θ0 the last factor is 1 and the weights are the renderer's.
//
// Next-event estimation at surface and medium vertices reaches the light through media and null surfaces
// (segment_transmittance), with MIS by the power heuristic (Veach 1997, Eq. 9.13) against BSDF or
// phase-function sampling on the solid-angle densities of the direction only: both strategies see the same
// transmittance (NEE estimates it, sampling reaches the emitter with the free-flight weights), so the weights
// of the two strategies sum to one for every path and the estimator stays unbiased.
//
// Depth (Mitsuba): the number of scattering vertices (surface or medium); a null surface crossed on the way,
// or the null lobe of another BSDF (mask, thin dielectric), is not one. A path with k scattering vertices is
// counted if k < max_depth. Russian roulette as render/path_tracer.h, on the path's estimate factor.
//
// Spectral MIS (SpectralFlights, the policy of every free flight of a path): `PerSegment` (volpath) draws
// each free flight with the per-segment channel balance of sample_free_flight; `PerPath` (volpathmis and the
// derivatives) drives every free flight by one hero channel and estimates f / mean_i(p_i) over the channels'
// path densities (render/hero_free_flight.h): the weight of a path stays below 3 where per-segment MIS
// compounds to 3^k over k segments in a strongly chromatic medium (whose heavy tails make a derivative's
// standard errors unreliable). `ratio` carries p_i / p_hero; the densities are detached.
#pragma once
#include "render/emitter_hit.h"
#include "render/flight_record.h"
#include "render/hero_free_flight.h"
#include "render/medium_sampling.h"
#include "render/mis.h"
#include "render/null_walk.h"
#include "render/path_tracer.h"
#include "render/volume_visibility.h"

#include <algorithm>

namespace penumbra {

enum class SpectralMIS { PerSegment, PerPath };

// A uniform channel for PerPath.
inline int sample_hero_channel(Sampler& sampler) { return std::min(int(sampler.next_1d() * 3.f), 2); }

// The spectral MIS rule of a path's free flights and its state: the hero channel (PerPath; drawn at the
// path's first free flight unless the caller drew it) and the density ratios p_i / p_hero so far (the caller
// multiplies them by each flight's `ratio`; PerSegment leaves it at 1).
struct SpectralFlights {
    SpectralMIS rule = SpectralMIS::PerPath;
    int hero = -1;
    Color3f ratio{1.f};

    HeroFreeFlight sample(const Medium& medium, const Ray& ray, float tmax, Sampler& sampler,
                          FlightRecord* record) {
        if (rule == SpectralMIS::PerSegment) {
            const FreeFlightSample ff = sample_free_flight(medium, ray.o, ray.d, tmax, sampler, record);
            return {ff.event, ff.t, ff.p, ff.weight};
        }
        if (hero < 0) hero = sample_hero_channel(sampler);
        return sample_free_flight_hero(medium, ray.o, ray.d, tmax, hero, sampler, record);
    }
    float mean_ratio() const { return (ratio.x + ratio.y + ratio.z) / 3.f; }
};

// How a chain ended (its last hit is the caller's: see sample_chain).
struct ChainEnd {
    enum class Kind { Surface, Medium, Escaped, Absorbed } kind = Kind::Absorbed;
    Vec3f p; // Medium: the scattering point
    const Medium* medium =
        nullptr;          // the medium at the end (Medium: the vertex's; Surface: the arriving side)
    float distance = 0.f; // reference distance from the chain's start to the end
};

// Samples a chain from `ray` (starting in `medium`, the ray counted by the caller): free flights in media by
// `flights`, crossing pure-null surfaces, until a scattering event, a surface with another BSDF, or escape.
// `hit` receives the chain's last hit (Surface: the vertex, its t the reference distance from the chain's
// start), `weight` the float free-flight weight (f/p_hero for PerPath), `chain` (optional) the pieces with
// their flight records. A walk stuck on coincident surfaces ends the chain as absorbed.
inline ChainEnd sample_chain(const Scene& scene, const Ray& ray, const Medium* medium,
                             SpectralFlights& flights, Sampler& sampler, LegChain* chain,
                             SurfaceInteraction3f& hit, Color3f& weight, RayCounter& rays) {
    ChainEnd end;
    weight = Color3f(1.f);
    const NullWalk w = walk_null_surfaces<NullWalkRule{.count_after_spawn = true}>(
        scene, ray, medium, rays, chain, hit,
        [&](const Medium* m, const Ray& r, float tmax, FlightRecord* record) {
            if (!m) return true;
            const HeroFreeFlight ff = flights.sample(*m, r, tmax, sampler, record);
            weight *= ff.weight;
            flights.ratio *= ff.ratio;
            if (ff.event == FreeFlightSample::Event::Absorbed || is_black(weight)) return false;
            if (ff.event != FreeFlightSample::Event::Scattered) return true;
            end.kind = ChainEnd::Kind::Medium;
            end.p = ff.p;
            end.medium = m;
            end.distance = ff.t;
            return false;
        });
    switch (w.end) {
    case NullWalk::End::Stopped:
        if (end.kind == ChainEnd::Kind::Medium) end.distance = w.travelled + end.distance;
        break;
    case NullWalk::End::Escaped:
        end.kind = ChainEnd::Kind::Escaped;
        end.distance = Infinity;
        break;
    case NullWalk::End::Surface:
        end.kind = ChainEnd::Kind::Surface;
        hit.t = w.travelled + hit.t;
        end.medium = w.medium;
        end.distance = hit.t;
        break;
    default:
        break;
    }
    return end;
}

// A vertex of the path in T: a surface vertex (its reference hit and its moving interaction) or a medium
// vertex (its reference point, its moving position and its medium).
template <typename T> struct VolVertex {
    bool surface = true;
    SurfaceInteraction3f hit;
    SurfaceInteraction<T> si; // T = Var (the reference reads hit)
    Vec3f p0;
    Vec3<T> p;
    Vec3f
        wi0; // medium vertex: the world direction it was reached from, reversed (toward the previous vertex)
    const Medium* medium =
        nullptr; // medium vertex: its medium; surface vertex: the side the path arrived from
};

// Radiance leaving the vertex x1 toward the previous vertex (the camera) at `prev` (moving), estimated along
// one sampled path: emission found at later vertices, next-event estimation at every vertex, and the
// material-form factors of every later step. x1's own factors (its emission, the camera and the first chain)
// are the caller's; `throughput` (float renders: the first chain's weight) only steers Russian roulette and
// scales the estimate. For a surface vertex x1.si.wi must be set (T = Var), for a medium vertex x1.wi0.
// `flights` carries the path's spectral MIS state after the first chain.
template <typename T, typename Geometry>
Color3<T> trace_volpath_from(const Scene& scene, Sampler& sampler, VolVertex<T> v, Vec3<T> prev,
                             SpectralFlights flights, const Geometry& geometry, const PathSettings& settings,
                             RayCounter& rays, Color3<T> throughput = Color3<T>(T(1))) {
    using std::abs;
    using std::sqrt;
    constexpr bool reference = std::is_same_v<T, float>;
    const BSDFContext ctx{TransportMode::Radiance};
    Color3<T> L(T(0));
    const unsigned max_depth = unsigned(settings.max_depth); // -1 wraps to "infinite"
    if (max_depth == 0) return L;
    const bool nee = !scene.emitters.empty();
    // The pieces of every chain, for re-evaluation on the moving geometry (the reference needs none).
    LegChain *chain = nullptr, *shadow = nullptr;
    if constexpr (!reference) {
        thread_local LegChain chain_pieces, shadow_pieces;
        chain = &chain_pieces, shadow = &shadow_pieces;
    }
    float eta = 1.f;
    float mean_ratio = flights.mean_ratio();

    for (unsigned depth = 0;;) { // depth: the scattering vertices before v
        // At the last scattering vertex a path goes on only through a null lobe.
        const BSDF* bsdf = v.surface ? v.hit.bsdf() : nullptr;
        const bool last = depth + 1 >= max_depth;
        if (last && !(bsdf && bsdf->has(BSDFNull))) break;

        // The vertex's scattering function toward a world direction, on the tape (the reference evaluates
        // none: its factors are the sampler's), and its float value and density for MIS.
        const Vec3<T> wi = reference ? Vec3<T>(T(0)) : normalize(prev - v.p);
        if (v.surface && !bsdf) break;
        const auto f_of = [&](const Vec3<T>& wo) -> Color3<T> {
            if (v.surface) return bsdf->eval(ctx, v.si, v.si.to_local(wo));
            return Color3<T>(v.medium->phase->template eval<T>(wi, wo));
        };
        Interaction3f ref;
        if (v.surface)
            ref = v.hit;
        else
            ref.p = v.p0, ref.t = 0.f;

        // The path's estimate factor: the throughput f/p_hero over the mean density ratio.
        const Color3<T> weight = throughput / T(mean_ratio);

        // Next-event estimation (through media and null surfaces).
        const bool smooth = v.surface ? bsdf->has(BSDFSmooth) : v.medium->sample_emitters;
        if (nee && smooth && !last) {
            const auto [ds, em_weight] = scene.sample_emitter_direction(ref, sampler.next_2d(), false);
            if (!is_black(em_weight)) {
                Color3f f0;
                float pdf;
                if (v.surface) {
                    const Vec3f local = v.hit.to_local(ds.d);
                    f0 = bsdf->eval(ctx, v.hit, local), pdf = bsdf->pdf(ctx, v.hit, local);
                } else {
                    pdf = v.medium->phase->pdf(v.wi0, ds.d), f0 = Color3f(pdf);
                }
                const Ray shadow_ray = std::isinf(ds.dist) ? ref.spawn_ray(ds.d) : ref.spawn_ray_to(ds.p);
                const Medium* shadow_medium =
                    v.surface ? target_medium(*v.hit.shape, v.hit.n, ds.d, v.medium) : v.medium;
                const Color3f tr = is_black(f0) ? Color3f(0.f)
                                                : segment_transmittance(scene, shadow_ray, shadow_medium,
                                                                        sampler, rays, nullptr, shadow);
                if (!is_black(tr)) {
                    const float w = ds.delta ? 1.f : mis_power(ds.pdf, pdf);
                    if constexpr (reference) {
                        L += weight * f0 * em_weight * tr * w;
                    } else {
                        const EmitterConnection<T> c = emitter_connection(ds, v.p, geometry);
                        const Vec3<T> end = c.finite ? c.light : v.p + c.wo;
                        L += weight * f_of(c.wo) * c.value *
                             chain_weight(*shadow, v.p, end, false, false, !c.finite, geometry) * T(w);
                    }
                }
            }
        } else {
            sampler.next_2d(); // keep the sample stream aligned
        }

        // BSDF or phase-function sampling in the reference configuration; a null lobe continues the path
        // without a scattering vertex.
        Vec3f d;
        float dir_pdf;
        bool delta = false, null = false;
        Color3f sampled_weight(1.f); // f/p in the reference configuration
        // After a delta lobe, its direction and smooth factor g / p on the tape (as render/path_tracer.h).
        Vec3<T> steered;
        Color3<T> delta_weight(T(1));
        if (v.surface) {
            const float u1 = sampler.next_1d();
            const auto [bs, bsdf_weight] = bsdf->sample(ctx, v.hit, u1, sampler.next_2d());
            if (is_black(bsdf_weight)) break;
            null = bs.sampled_type == BSDFNull;
            if (last && !null) break;
            d = v.hit.to_world(bs.wo);
            dir_pdf = bs.pdf;
            delta = (bs.sampled_type & BSDFDelta) != 0;
            sampled_weight = bsdf_weight;
            eta *= bs.eta;
            if constexpr (!reference) {
                if (delta) {
                    SurfaceInteraction<T> here = v.si;
                    here.wi = here.to_local(wi);
                    steered = delta_step(*bsdf, v.hit, here, bs, delta_weight);
                }
            }
        } else {
            const auto [wo, pdf] = v.medium->phase->sample(v.wi0, sampler.next_2d());
            if (!(pdf > 0.f)) break;
            d = wo;
            dir_pdf = pdf;
        }

        // Russian roulette on the estimate factor after the sampling weight (without the free-flight ratio),
        // before the chain is traced (Mitsuba's volpath); a null lobe is not a scattering vertex.
        const bool roulette = !null && depth + 1 >= unsigned(settings.rr_depth);
        float q = 1.f;
        if (roulette) {
            const Color3f so_far(detach(throughput.x), detach(throughput.y), detach(throughput.z));
            q = roulette_survival(so_far * sampled_weight, eta, mean_ratio);
            if (sampler.next_1d() >= q) break;
        }

        // The chain to the next vertex; its hit lands in v.hit.
        const Medium* medium = v.surface ? target_medium(*v.hit.shape, v.hit.n, d, v.medium) : v.medium;
        const Ray ray = v.surface ? v.hit.spawn_ray(d) : Ray(v.p0, d);
        ++rays.rays;
        Color3f flight;
        const ChainEnd end = sample_chain(scene, ray, medium, flights, sampler, chain, v.hit, flight, rays);
        if (end.kind == ChainEnd::Kind::Absorbed) break;
        mean_ratio = flights.mean_ratio();

        // The next vertex in T (its moving interaction next_si and position x) and the step's factor
        // f/p_σ · chain weight · G J / G0.
        SurfaceInteraction<T> next_si;
        Vec3<T> x;
        Color3<T> step;
        if constexpr (reference) {
            step = sampled_weight * flight;
            // A surface vertex keeps its hit: its wi is already -d, the direction of the chain's last ray.
            x = end.kind == ChainEnd::Kind::Surface ? v.hit.p : end.p;
        } else {
            T measure(1.f);
            if (delta && end.kind == ChainEnd::Kind::Surface) {
                // No area integral after a delta lobe: the vertex where its direction meets the surface.
                next_si = geometry.ray_vertex(v.hit, v.p, steered);
                x = next_si.p;
                next_si.wi = next_si.to_local(-steered);
            } else if (delta && end.kind == ChainEnd::Kind::Medium) {
                x = v.p + steered * T(norm(end.p - v.p0)); // at its free-flight distance along the direction
            } else if (end.kind == ChainEnd::Kind::Surface) {
                next_si = geometry.vertex(v.hit);
                x = next_si.p;
                const Vec3<T> to = x - v.p;
                const T dist2 = squared_norm(to);
                const Vec3<T> w = to / sqrt(dist2);
                next_si.wi = next_si.to_local(-w);
                measure = relative_change(abs(dot(next_si.n, w)) / dist2 * geometry.jacobian(v.hit));
            } else if (end.kind == ChainEnd::Kind::Medium) {
                T jacobian;
                x = geometry.medium_vertex(end.p, end.medium, jacobian);
                measure = relative_change(jacobian / squared_norm(x - v.p));
            }
            const bool escaped = end.kind == ChainEnd::Kind::Escaped;
            const Vec3<T> wo = delta ? steered : escaped ? Vec3<T>(d) : normalize(x - v.p);
            const Color3<T> f = delta ? delta_weight : f_of(wo) / T(dir_pdf);
            step = f *
                   chain_weight(*chain, v.p, escaped ? v.p + wo : x, true, end.kind == ChainEnd::Kind::Medium,
                                escaped, geometry) *
                   (delta ? T(1.f) : measure);
        }

        // Emission found at the end (a surface or the environment), weighted against emitter sampling.
        if (end.kind != ChainEnd::Kind::Medium) {
            for_each_emitter_hit(
                scene, ref, d, v.hit, [&](const Emitter* e, const Color3f& Le, float em_pdf) {
                    const float w = (delta || !smooth) ? 1.f : mis_power(dir_pdf, em_pdf);
                    if constexpr (reference) {
                        L += throughput * step * Le * (w / mean_ratio / q);
                    } else {
                        const Color3<T> le =
                            end.kind == ChainEnd::Kind::Surface
                                ? e->eval(next_si)
                                : e->eval_environment(geometry.direction_to_reference_light(*e, d) +
                                                      (delta ? steered - Vec3<T>(d) : Vec3<T>(T(0))));
                        L += throughput * step * le * T(w / mean_ratio / q);
                    }
                });
        }
        if (end.kind == ChainEnd::Kind::Escaped) break;
        throughput *= step;
        if (roulette) throughput /= T(q);

        prev = v.p;
        v.surface = end.kind == ChainEnd::Kind::Surface;
        if constexpr (!reference) v.si = next_si;
        v.p0 = v.surface ? v.hit.p : end.p;
        v.p = x;
        v.wi0 = -d;
        v.medium = end.medium;
        if (!null) ++depth;
    }
    return L;
}

// Radiance arriving at the sensor along `primary` (the `volpath` and `volpathmis` integrators): the chain
// from the camera through the sensor's medium and null surfaces to the first vertex x1, the emission seen
// there, and trace_volpath_from for the rest of the path.
inline Color3f trace_volpath(const Scene& scene, Sampler& sampler, const Ray& primary,
                             const PathSettings& settings, SpectralMIS spectral, RayCounter& rays) {
    if (settings.max_depth == 0) return Color3f(0.f);
    SpectralFlights flights{spectral};
    VolVertex<float> x1;
    Color3f flight;
    const ChainEnd end =
        sample_chain(scene, primary, sensor_medium(scene), flights, sampler, nullptr, x1.hit, flight, rays);
    if (end.kind == ChainEnd::Kind::Absorbed) return Color3f(0.f);
    Color3f L(0.f);
    if (end.kind != ChainEnd::Kind::Medium && !settings.hide_emitters) {
        Interaction3f camera;
        camera.p = primary.o;
        for_each_emitter_hit(scene, camera, primary.d, x1.hit,
                             [&](const Emitter*, const Color3f& Le, float) { L += Le; });
    }
    L *= flight / flights.mean_ratio();
    if (end.kind == ChainEnd::Kind::Escaped) return L;
    x1.surface = end.kind == ChainEnd::Kind::Surface;
    x1.p0 = x1.p = x1.surface ? x1.hit.p : end.p;
    x1.wi0 = -primary.d;
    x1.medium = end.medium;
    return L + trace_volpath_from<float>(scene, sampler, x1, primary.o, flights, ReferenceGeometry{},
                                         settings, rays, flight);
}

} // namespace penumbra
