// Sampling participating media along a ray segment: free-flight distances (where a path scatters next) and
// transmittance. Homogeneous media use the closed forms; heterogeneous media track collisions against the
// medium's piecewise-constant grey majorants (Medium::majorants): weighted delta tracking for free flights,
// ratio tracking with Russian roulette for transmittance (Novák et al. 2014, Kutz et al. 2017).
//
// Chromatic media (per-channel sigma_t): the distance is drawn with one channel's density, the channel chosen
// uniformly, and the weight divides by the average of the three channels' densities (the one-sample balance
// heuristic over channels; Mitsuba's volpathmis does the same, its volpath divides by the chosen channel's
// density alone, which is unbiased only while every channel has sigma_t > 0). Heterogeneous media use one
// grey majorant, so every channel shares the collision density and the channel choice is not needed.
#pragma once
#include "core/sampler.h"
#include "render/flight_record.h"
#include "scene/medium.h"

#include <cmath>

namespace penumbra {

struct FreeFlightSample {
    enum class Event { Passed, Scattered, Absorbed };
    Event event = Event::Passed;
    float t = Infinity; // distance of the scattering event (Scattered)
    Vec3f p;            // its position
    // Scattered: Tr(0, t) sigma_s(p) / pdf(t); Passed: Tr(0, tmax) / P(pass); Absorbed: 0 (the path ends).
    // Unbiased estimates in heterogeneous media (delta tracking).
    Color3f weight{0.f, 0.f, 0.f};
    // Per channel c, the density of this outcome had channel c's distance sampling been used: the distance
    // density (Scattered, 1/length) or the probability of passing (Passed). Exact in homogeneous media; in
    // heterogeneous media these are left at 0 (use free_flight_pdf for MIS).
    Color3f pdf{0.f, 0.f, 0.f};
};

// The tentative collisions of delta and ratio tracking along o + t d, t in [0, tmax): exponential steps with
// the medium's majorant m on each of its majorant segments (memoryless: a step past a segment's end restarts
// at the next segment's start). Calls f(t, p, m) at each; stops when f returns false.
template <typename F>
void for_each_tentative_collision(const Medium& medium, const Vec3f& o, const Vec3f& d, float tmax,
                                  Sampler& sampler, F&& f) {
    medium.majorants(o, d, 0.f, tmax, [&](float t0, float t1, float m) {
        if (!(m > 0.f)) return true; // nothing to collide with on this segment
        for (float t = t0;;) {
            t -= std::log1p(-sampler.next_1d()) / m;
            if (t >= t1) return true;
            if (!f(t, o + d * t, m)) return false;
        }
    });
}

// Samples where a ray (origin o, unit direction d) travelling in `medium` first scatters within [0, tmax).
// `record` (optional) keeps the events of a heterogeneous medium (render/flight_record.h; a homogeneous
// medium's weight has a closed form).
FreeFlightSample sample_free_flight(const Medium& medium, const Vec3f& o, const Vec3f& d, float tmax,
                                    Sampler& sampler, FlightRecord* record = nullptr);

// An unbiased estimate of the per-channel transmittance exp(-∫_0^tmax sigma_t) along o + t d (exact for
// homogeneous media; ratio tracking otherwise).
// homogeneous; ratio tracking otherwise). `record` (optional) keeps the collisions (render/flight_record.h).
Color3f transmittance(const Medium& medium, const Vec3f& o, const Vec3f& d, float tmax, Sampler& sampler,
                      FlightRecord* record = nullptr);

// A deterministic density of the free-flight outcome for MIS weights (bidirectional estimators): the
// channel-averaged density of scattering at distance t (scattered) or of passing a segment of length t (not
// scattered). Exact for homogeneous media; heterogeneous media use the density of a homogeneous medium with
// sigma_t averaged (midpoint rule, 16 steps) along the segment — any positive function shared by all
// strategies keeps MIS unbiased.
float free_flight_pdf(const Medium& medium, const Vec3f& o, const Vec3f& d, float t, bool scattered);

} // namespace penumbra
