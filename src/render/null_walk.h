// The straight walk through index-matched boundaries, written once for every estimator that follows a ray
// through media (paper 001 §5.2, Algorithm 1's straight segments; pbrt-v4's SampleT_maj plays this part for
// majorant walks): intersect, let the caller's segment policy act on the piece of the ray in the current
// medium — sample a free flight, estimate the transmittance, or nothing —, cross the surface if the rule
// allows it (the medium changes by target_medium) and go on, at most MaxNullCrossings times (rays stuck on
// coincident surfaces). With a LegChain the walk records every piece and the surface that bounds it, for
// re-evaluation on a moving geometry (render/flight_record.h).
//
// NullWalkRule names how the callers differ, kept to the ray: psdr's deterministic sample budget counts the
// rays, so when a ray is counted is part of the result.
#pragma once
#include "render/flight_record.h"
#include "render/integrator.h"
#include "scene/scene.h"

namespace penumbra {

// A bound on the surfaces a walk crosses, against rays stuck on coincident surfaces.
constexpr int MaxNullCrossings = 256;

struct NullWalkRule {
    bool every_surface = false;     // cross every surface (the walk from the sensor that finds a medium),
                                    // not only those whose BSDF is a pure `null`
    bool bounded = false;           // a segment: rays keep the remaining tmax (ray_beyond) and the walk ends
                                    // where it runs out; otherwise each crossing spawns an unbounded ray
    bool count_after_spawn = false; // count each ray after spawning it (the caller counted the first), not
                                    // before each intersection
    bool hit_after_bound_ends = false; // after MaxNullCrossings crossings the next hit ends the walk as a
                                       // surface (bdpt's random walk), instead of the walk being exhausted
};

inline bool is_pure_null(const SurfaceInteraction3f& si) {
    const BSDF* bsdf = si.bsdf();
    return bsdf && bsdf->flags() == BSDFNull;
}

// The rest of `ray` beyond its surface hit `si`: offset off the surface, tmax shortened by the distance
// covered (not positive when nothing is left).
inline Ray ray_beyond(const Ray& ray, const SurfaceInteraction3f& si) {
    Ray next = si.spawn_ray(ray.d);
    next.tmax = ray.tmax - si.t - dot(next.o - si.p, ray.d);
    return next;
}

// How a walk ended: the segment policy stopped it (a scattering event, absorption), at a surface it does not
// cross (the walk's last hit), with the ray escaping (or, bounded, meeting nothing before tmax), at the end
// of a bounded segment just beyond a crossing, or after MaxNullCrossings crossings.
struct NullWalk {
    enum class End { Stopped, Surface, Escaped, Reached, Exhausted };
    End end = End::Exhausted;
    Ray ray;                        // the last ray traced (Reached, Exhausted: the next one)
    const Medium* medium = nullptr; // the medium of the last piece (Reached, Exhausted: beyond the crossing)
    float travelled = 0.f;          // distance from the walk's start to ray.o, summed over the hits
};

// Walks `ray` from `medium` (null: vacuum); `hit` receives each hit, the walk's last at its end.
// segment(medium, ray, end, record) acts on each piece [0, end) of a ray in `medium` (end: the hit's
// distance, or the ray's tmax — infinite when unbounded — if it hits nothing) with the piece's FlightRecord
// (null without `chain`), and returns false to stop the walk there.
template <NullWalkRule Rule, typename Segment>
NullWalk walk_null_surfaces(const Scene& scene, const Ray& ray, const Medium* medium, RayCounter& rays,
                            LegChain* chain, SurfaceInteraction3f& hit, Segment&& segment) {
    NullWalk w;
    w.ray = ray;
    w.medium = medium;
    if (chain) chain->clear();
    for (int crossing = 0;; ++crossing) {
        if constexpr (!Rule.count_after_spawn) ++rays.rays;
        hit = scene.intersect(w.ray);
        const float end = hit.is_valid() ? hit.t : (Rule.bounded ? w.ray.tmax : Infinity);
        LegPiece* piece = chain ? &chain->add(w.medium, w.travelled) : nullptr;
        if (piece) piece->bound = hit;
        if (!segment(w.medium, w.ray, end, piece ? &piece->record : nullptr)) {
            w.end = NullWalk::End::Stopped;
            return w;
        }
        if (!hit.is_valid()) {
            w.end = NullWalk::End::Escaped;
            return w;
        }
        if ((Rule.hit_after_bound_ends && crossing == MaxNullCrossings) ||
            !(Rule.every_surface || is_pure_null(hit))) {
            w.end = NullWalk::End::Surface;
            return w;
        }
        w.medium = target_medium(*hit.shape, hit.n, w.ray.d, w.medium);
        w.travelled += hit.t;
        w.ray = Rule.bounded ? ray_beyond(w.ray, hit) : hit.spawn_ray(w.ray.d);
        if constexpr (Rule.count_after_spawn) ++rays.rays;
        if (Rule.bounded && !(w.ray.tmax > 0.f)) {
            w.end = NullWalk::End::Reached;
            return w;
        }
        if (!Rule.hit_after_bound_ends && crossing + 1 == MaxNullCrossings) return w; // Exhausted
    }
}

// A segment policy that does nothing (the walk only finds surfaces or media).
inline bool no_segment_action(const Medium*, const Ray&, float, FlightRecord*) { return true; }

} // namespace penumbra
