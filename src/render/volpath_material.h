// Volumetric path tracing in material form (paper 001 §4.1, §5.1, §6.2): the estimator of the radiative
// transfer equation written once on the scalar type T over a Geometry — T = float on the reference geometry
// (a volumetric path tracer), T = Var on the moving geometry (the interior term of the generalized
// differential path integral with surface and medium vertices).
//
// Paths are sampled in the reference configuration with float arithmetic (BSDF and phase sampling, free
// flights, next-event estimation, MIS and Russian roulette are detached). Each step from a vertex x_{i-1} to
// the next vertex x_i (a surface vertex or a medium vertex, reached through index-matched `null` surfaces)
// contributes
//     f(x_{i-2} → x_{i-1} → x_i) / p_σ  ·  Tr σ_s / p_t (free-flight weights, render/flight_record.h)
//     ·  G(x_{i-1}, x_i) J(x_i) / G_0,
// with G = |n_i · ω| / ℓ² for a surface vertex and 1 / ℓ² for a medium vertex (its measure is the volume,
// J = dV(x)/dV(p), Eq. 46). At θ0 the last factor is 1 and the weights are the renderer's.
//
// Chromatic media: one hero channel drives every free flight of a path and the estimate is f / mean_i(p_i)
// over the channels' path densities (render/hero_free_flight.h, as `volpathmis`): the weight of a path stays
// below 3 where per-segment channel MIS compounds to 3^k over k segments (whose heavy tails make the
// derivative's standard errors unreliable). `ratio` carries p_i / p_hero; the densities are detached.
#pragma once
#include "render/emitter_hit.h"
#include "render/flight_record.h"
#include "render/hero_free_flight.h"
#include "render/medium_sampling.h"
#include "render/mis.h"
#include "render/null_walk.h"
#include "render/path_tracer.h"
#include "render/volume_visibility.h"

#include <vector>

namespace penumbra {

// How a chain ended.
struct ChainEnd {
    enum class Kind { Surface, Medium, Escaped, Absorbed } kind = Kind::Absorbed;
    SurfaceInteraction3f si; // Surface: the vertex (t: its reference distance from the chain's start)
    Vec3f p;                 // Medium: the scattering point
    const Medium* medium =
        nullptr;          // the medium at the end (Medium: the vertex's; Surface: the arriving side)
    float distance = 0.f; // reference distance from the chain's start to the end
};

// Samples a chain from `ray` (starting in `medium`): free flights in media driven by channel `hero`, crossing
// pure-null surfaces, until a scattering event, a surface with another BSDF, or escape. `weight` receives the
// float free-flight weight f/p_hero, `ratio` is multiplied by the chain's density ratios p_i / p_hero.
// Crossings are bounded (rays stuck on coincident surfaces end the chain as absorbed).
inline ChainEnd sample_chain(const Scene& scene, Ray ray, const Medium* medium, int hero, Sampler& sampler,
                             LegChain& chain, Color3f& weight, Color3f& ratio, RayCounter& rays) {
    ChainEnd end;
    weight = Color3f(1.f);
    const NullWalk w = walk_null_surfaces<NullWalkRule{.count_after_spawn = true}>(
        scene, ray, medium, rays, &chain, end.si,
        [&](const Medium* m, const Ray& r, float tmax, FlightRecord* record) {
            if (!m) return true;
            const HeroFreeFlight ff = sample_free_flight_hero(*m, r.o, r.d, tmax, hero, sampler, record);
            weight *= ff.weight;
            ratio *= ff.ratio;
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
        end.si.t = w.travelled + end.si.t;
        end.medium = w.medium;
        end.distance = end.si.t;
        break;
    default:
        break;
    }
    return end;
}

// Where the line through a and b meets the plane of the moving triangle of `hit` (a crossing of a null
// surface, which is not a path vertex: it slides along the moving segment).
template <typename T, typename Geometry>
Vec3<T> crossing_point(const Geometry& geometry, const SurfaceInteraction3f& hit, const Vec3<T>& a,
                       const Vec3<T>& b) {
    const uint32_t* i = &hit.shape->mesh.indices[3 * size_t(hit.prim_index)];
    const Vec3<T> q0 = geometry.position(*hit.shape, i[0]);
    const Vec3<T> n =
        cross(geometry.position(*hit.shape, i[1]) - q0, geometry.position(*hit.shape, i[2]) - q0);
    const Vec3<T> ab = b - a;
    return a + ab * (dot(n, q0 - a) / dot(n, ab));
}

// The weight of a chain on the moving segment a → b: free-flight weights (`free_flight`, the last piece
// scattering at b when `scattered`) or transmittance estimates, piece by piece between the crossings. With
// `to_infinity` b only gives the direction and the last piece (vacuum, or a medium that is empty there)
// contributes 1.
template <typename T, typename Geometry>
Color3<T> chain_weight(const LegChain& chain, const Vec3<T>& a, const Vec3<T>& b, bool free_flight,
                       bool scattered, bool to_infinity, const Geometry& geometry) {
    Color3<T> w(T(1));
    Vec3<T> start = a;
    for (int k = 0; k < chain.count; ++k) {
        const LegPiece& piece = chain.pieces[size_t(k)];
        const bool last = k + 1 == chain.count;
        if (last && to_infinity) break;
        const Vec3<T> end = last ? b : crossing_point(geometry, piece.bound, a, b);
        if (piece.medium)
            w *= free_flight ? flight_weight(*piece.medium, piece.record, last && scattered, start, end)
                             : transmittance_weight(*piece.medium, piece.record, start, end);
        start = end;
    }
    return w;
}

// A vertex of the path in T: a surface vertex (its reference hit and its moving interaction) or a medium
// vertex (its reference point, its moving position and its medium).
template <typename T> struct VolVertex {
    bool surface = true;
    SurfaceInteraction3f hit;
    SurfaceInteraction<T> si;
    Vec3f p0;
    Vec3<T> p;
    const Medium* medium =
        nullptr; // medium vertex: its medium; surface vertex: the side the path arrived from
};

// Radiance leaving the vertex x1 toward the previous vertex (the camera) at `prev` (moving; `prev0` in the
// reference), estimated along one sampled path: emission found at later vertices, next-event estimation at
// every vertex, and the material-form factors of every later step. x1's own factors (its emission, the camera
// and the first chain) are the caller's. For a surface vertex x1.si.wi must be set.
// `hero` is the path's channel and `ratio` its density ratios so far (the first chain's).
template <typename T, typename Geometry>
Color3<T> trace_volpath_from(const Scene& scene, Sampler& sampler, VolVertex<T> v, Vec3<T> prev, Vec3f prev0,
                             int hero, Color3f ratio, const Geometry& geometry, const PathSettings& settings,
                             RayCounter& rays) {
    using std::abs;
    using std::sqrt;
    constexpr bool reference = std::is_same_v<T, float>;
    const BSDFContext ctx{TransportMode::Radiance};
    Color3<T> L(T(0)), throughput(T(1));
    const unsigned max_depth = unsigned(settings.max_depth); // -1 wraps to "infinite"
    const bool nee = !scene.emitters.empty();
    thread_local LegChain chain, shadow;
    float eta = 1.f;

    for (unsigned depth = 0; depth + 1 < max_depth; ++depth) {
        // The vertex's scattering function toward a world direction, on the tape, and its float value and
        // density for MIS.
        const Vec3f wi0 = normalize(prev0 - (v.surface ? v.hit.p : v.p0));
        const Vec3<T> wi = normalize(prev - v.p);
        const BSDF* bsdf = v.surface ? v.hit.bsdf() : nullptr;
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
        const Color3<T> weight = throughput / T((ratio.x + ratio.y + ratio.z) / 3.f);

        // Next-event estimation (through media and null surfaces).
        const bool smooth = v.surface ? bsdf->has(BSDFSmooth) : v.medium->sample_emitters;
        if (nee && smooth) {
            const auto [ds, em_weight] = scene.sample_emitter_direction(ref, sampler.next_2d(), false);
            if (!is_black(em_weight)) {
                Color3f f0;
                float pdf;
                if (v.surface) {
                    const Vec3f local = v.hit.to_local(ds.d);
                    f0 = bsdf->eval(ctx, v.hit, local), pdf = bsdf->pdf(ctx, v.hit, local);
                } else {
                    pdf = v.medium->phase->pdf(wi0, ds.d), f0 = Color3f(pdf);
                }
                const Ray shadow_ray = std::isinf(ds.dist) ? ref.spawn_ray(ds.d) : ref.spawn_ray_to(ds.p);
                const Medium* shadow_medium =
                    v.surface ? target_medium(*v.hit.shape, v.hit.n, ds.d, v.medium) : v.medium;
                const Color3f tr = is_black(f0) ? Color3f(0.f)
                                                : segment_transmittance(scene, shadow_ray, shadow_medium,
                                                                        sampler, rays, nullptr, &shadow);
                if (!is_black(tr)) {
                    const float w = ds.delta ? 1.f : mis_power(ds.pdf, pdf);
                    if constexpr (reference) {
                        L += weight * f0 * em_weight * tr * w;
                    } else {
                        const EmitterConnection<T> c = emitter_connection(ds, v.p, geometry);
                        const Vec3<T> end = c.finite ? c.light : v.p + c.wo;
                        L += weight * f_of(c.wo) * c.value *
                             chain_weight(shadow, v.p, end, false, false, !c.finite, geometry) * T(w);
                    }
                }
            }
        } else {
            sampler.next_2d(); // keep the sample stream aligned
        }

        // BSDF or phase-function sampling in the reference configuration.
        Vec3f d;
        float dir_pdf;
        bool delta = false;
        Color3f delta_weight(1.f);
        const float u1 = sampler.next_1d();
        const Vec2f u2 = sampler.next_2d();
        if (v.surface) {
            const auto [bs, weight] = bsdf->sample(ctx, v.hit, u1, u2);
            if (is_black(weight)) break;
            d = v.hit.to_world(bs.wo);
            dir_pdf = bs.pdf;
            delta = (bs.sampled_type & BSDFDelta) != 0;
            delta_weight = weight;
            eta *= bs.eta;
        } else {
            const auto [wo, pdf] = v.medium->phase->sample(wi0, u2);
            if (!(pdf > 0.f)) break;
            d = wo;
            dir_pdf = pdf;
        }
        const Medium* medium = v.surface ? target_medium(*v.hit.shape, v.hit.n, d, v.medium) : v.medium;
        Ray ray = v.surface ? v.hit.spawn_ray(d) : Ray(v.p0, d);
        ++rays.rays;
        Color3f flight;
        const ChainEnd end = sample_chain(scene, ray, medium, hero, sampler, chain, flight, ratio, rays);
        if (end.kind == ChainEnd::Kind::Absorbed) break;
        const float mean_ratio = (ratio.x + ratio.y + ratio.z) / 3.f;

        // The next vertex in T and the step's factor f/p_σ · chain weight · G J / G0.
        VolVertex<T> next;
        Color3<T> step;
        if constexpr (reference) {
            step = (delta ? delta_weight : f_of(d) / dir_pdf) * flight;
            if (end.kind == ChainEnd::Kind::Surface) {
                next.si = end.si;
                next.si.wi = end.si.to_local(d * -1.f);
                next.p = end.si.p;
            } else if (end.kind == ChainEnd::Kind::Medium) {
                next.p = end.p;
            }
        } else {
            Vec3<T> x;
            T measure(1.f);
            if (end.kind == ChainEnd::Kind::Surface) {
                next.si = geometry.vertex(end.si);
                x = next.si.p;
                const Vec3<T> to = x - v.p;
                const T dist2 = squared_norm(to);
                const Vec3<T> w = to / sqrt(dist2);
                next.si.wi = next.si.to_local(-w);
                measure = relative_change(abs(dot(next.si.n, w)) / dist2 * geometry.jacobian(end.si));
            } else if (end.kind == ChainEnd::Kind::Medium) {
                T jacobian;
                x = geometry.medium_vertex(end.p, end.medium, jacobian);
                measure = relative_change(jacobian / squared_norm(x - v.p));
            }
            const bool escaped = end.kind == ChainEnd::Kind::Escaped;
            const Vec3<T> wo = escaped ? Vec3<T>(d) : normalize(x - v.p);
            const Color3<T> f = delta ? Color3<T>(delta_weight) : f_of(wo) / T(dir_pdf);
            step = f *
                   chain_weight(chain, v.p, escaped ? v.p + wo : x, true, end.kind == ChainEnd::Kind::Medium,
                                escaped, geometry) *
                   (delta ? T(1.f) : measure);
            next.p = x;
        }

        // Emission found at the end (a surface or the environment), weighted against emitter sampling.
        if (end.kind != ChainEnd::Kind::Medium) {
            SurfaceInteraction3f seen = end.si;
            for_each_emitter_hit(scene, ref, d, seen, [&](const Emitter* e, const Color3f& Le, float em_pdf) {
                const float w = (delta || !smooth) ? 1.f : mis_power(dir_pdf, em_pdf);
                if constexpr (reference) {
                    L += throughput * step * Le * (w / mean_ratio);
                } else {
                    const Color3<T> le =
                        end.kind == ChainEnd::Kind::Surface
                            ? e->eval(next.si)
                            : e->eval_environment(geometry.direction_to_reference_light(*e, d));
                    L += throughput * step * le * T(w / mean_ratio);
                }
            });
        }
        if (end.kind == ChainEnd::Kind::Escaped) break;
        throughput *= step;

        prev = v.p;
        prev0 = v.surface ? v.hit.p : v.p0;
        next.surface = end.kind == ChainEnd::Kind::Surface;
        next.hit = end.si;
        next.p0 = next.surface ? end.si.p : end.p;
        next.medium = end.medium;
        v = next;

        // Russian roulette on the estimate factor (without the free-flight ratio).
        if (depth + 1 >= unsigned(settings.rr_depth) &&
            !survives_roulette(throughput, eta, sampler, mean_ratio))
            break;
    }
    return L;
}

} // namespace penumbra
