// What a free flight or a transmittance estimate drew along one straight leg of a path, kept so that the
// same estimate can be re-evaluated on the moving leg of the material form (paper 001 §4.1, §6.2): the events
// are sampled once, detached, in the reference configuration; their weights are functions of θ.
//
// Tentative collisions are drawn at reference distances t along a leg of reference length ℓ0. On the moving
// leg a(θ) → b(θ) of length ℓ(θ) they sit at the same fractions t/ℓ0, i.e. they form a Poisson process of
// rate μ ℓ0/ℓ per unit length, so that
//   ratio tracking    Tr(θ) ≈ Π_j (1 − σt(y_j(θ)) ℓ/(μ ℓ0))                  (unbiased for every θ),
//   delta tracking    Tr(θ) σs(x(θ)) / p ≈ Π_j (μ − σt(y_j) ℓ/ℓ0) / (μ P_null,j) · σs(x) / (μ P_real)
// (the null-collision form of Miller et al. 2019 with detached event probabilities P); at θ0 these are the
// weights the samplers use. Homogeneous media keep the closed forms exp(−σt ℓ(θ)) over the detached density.
// The change of measure of the vertex itself, ℓ0²/ℓ² · J, is the caller's. A leg that crosses index-matched
// surfaces is a chain of such pieces (LegChain, recorded by render/null_walk.h).
#pragma once
#include "scene/interaction.h"
#include "scene/medium.h"
#include "scene/shape.h"

#include <vector>

namespace penumbra {

struct FlightRecord {
    struct Collision {
        float t;           // reference distance from the leg's start
        float majorant;    // μ there
        float probability; // detached probability of the event taken (null collision; RR survival for ratio
                           // tracking)
    };
    float length = 0.f; // reference length ℓ0 of the leg
    float pdf = 1.f;    // homogeneous: the density of the outcome (1/length or probability)
    float real_majorant = 0.f, real_probability = 1.f; // heterogeneous free flight: the real collision
    std::vector<Collision> collisions;

    void reset(float leg_length) {
        length = leg_length;
        pdf = 1.f;
        real_majorant = 0.f;
        real_probability = 1.f;
        collisions.clear();
    }
};

// One straight piece of a chain of legs through null surfaces: travelled in `medium` (null: vacuum) and
// ending at `bound`, the surface its ray met (invalid: none), which is crossed unless it is the chain's end.
struct LegPiece {
    const Medium* medium = nullptr;
    SurfaceInteraction3f bound;
    float start = 0.f; // reference distance of the piece's start from the chain's start
    FlightRecord record;
};

// The pieces of one chain (kept across steps to reuse their storage).
struct LegChain {
    std::vector<LegPiece> pieces;
    int count = 0;

    LegPiece& add(const Medium* medium, float start) {
        if (count == int(pieces.size())) pieces.emplace_back();
        LegPiece& p = pieces[size_t(count++)];
        p.medium = medium;
        p.bound = SurfaceInteraction3f();
        p.start = start;
        return p;
    }
    void clear() { count = 0; }
};

namespace flight_detail {
template <typename T> Color3<T> exp_neg(const Color3<T>& v) {
    using std::exp;
    return {exp(-v.x), exp(-v.y), exp(-v.z)};
}
} // namespace flight_detail

// The free-flight weight of a leg a → b (b the scattering point when `scattered`, else the leg's end):
// Tr(a, b) σs(b) / p (scattered) or Tr(a, b) / P (passed), re-evaluated on the moving leg.
template <typename T>
Color3<T> flight_weight(const Medium& medium, const FlightRecord& r, bool scattered, const Vec3<T>& a,
                        const Vec3<T>& b) {
    using std::sqrt;
    const Vec3<T> ab = b - a;
    const T length = sqrt(squared_norm(ab));
    if (medium.is_homogeneous()) {
        const Color3<T> sigma_t = medium.sigma_t(a);
        const Color3<T> tr = flight_detail::exp_neg(sigma_t * length);
        return (scattered ? tr * sigma_t * medium.albedo(b) : tr) / T(r.pdf);
    }
    const T stretch = length / T(r.length);
    Color3<T> w(T(1));
    for (const FlightRecord::Collision& c : r.collisions) {
        const Vec3<T> y = a + ab * T(c.t / r.length);
        w *= (Color3<T>(T(c.majorant)) - medium.sigma_t(y) * stretch) / T(c.majorant * c.probability);
    }
    if (scattered) w *= medium.sigma_t(b) * medium.albedo(b) / T(r.real_majorant * r.real_probability);
    return w;
}

// The transmittance estimate of a leg a → b (ratio tracking, its Russian roulette detached), re-evaluated on
// the moving leg; exact in homogeneous media.
template <typename T>
Color3<T> transmittance_weight(const Medium& medium, const FlightRecord& r, const Vec3<T>& a,
                               const Vec3<T>& b) {
    using std::sqrt;
    const Vec3<T> ab = b - a;
    const T length = sqrt(squared_norm(ab));
    if (medium.is_homogeneous()) return flight_detail::exp_neg(medium.sigma_t(a) * length);
    const T stretch = length / T(r.length);
    Color3<T> tr(T(1));
    for (const FlightRecord::Collision& c : r.collisions) {
        const Vec3<T> y = a + ab * T(c.t / r.length);
        tr *= (Color3<T>(T(1)) - medium.sigma_t(y) * (stretch / T(c.majorant))) / T(c.probability);
    }
    return tr;
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

} // namespace penumbra
