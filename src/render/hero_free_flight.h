// Free-flight sampling for spectral MIS over whole paths (`volpathmis`; pbrt-v4's VolPathIntegrator, §14.2.2
// of Physically Based Rendering 4th ed.): one hero channel c, chosen once per path, drives every distance and
// collision decision; each decision multiplies the path weight f/p_c and the ratios r_i = p_i / p_c of the
// densities that channel i's sampling would have had for the same decision. The path estimate
// f / ((1/3) Σ_i p_i) = (f/p_c) / mean(r) is the one-sample balance heuristic over channels for the whole
// path.
//
// Homogeneous media use the chromatic majorant sigma_t itself (no null collisions): scattering at t has
// density sigma_t,i exp(-sigma_t,i t) under channel i, passing a segment of length s probability
// exp(-sigma_t,i s). Heterogeneous media use the medium's grey majorant m: tentative collisions have the same
// density for every channel, and at a collision the hero channel picks absorption, scattering or a null
// collision with probabilities sigma_a,c/m, sigma_s,c/m, sigma_n,c/m (channel i: sigma_x,i/m), so the weight
// and the ratios are both multiplied by sigma_x / sigma_x,c (null-scattering path integral, Miller et al.
// 2019).
#pragma once
#include "render/medium_sampling.h"

namespace penumbra {

struct HeroFreeFlight {
    FreeFlightSample::Event event = FreeFlightSample::Event::Passed;
    float t = Infinity;  // distance of the scattering event (Scattered)
    Vec3f p;             // its position
    Color3f weight{1.f}; // factor of the path weight f/p_c (includes sigma_s at a scattering event)
    Color3f ratio{1.f};  // factor of the density ratios p_i/p_c
};

// Samples where a ray (origin o, unit direction d) in `medium` first scatters within [0, tmax), driven by
// channel `hero` (0, 1 or 2). `record` (optional) keeps the events for re-evaluation on a moving leg
// (render/flight_record.h: its densities and probabilities are the hero channel's).
HeroFreeFlight sample_free_flight_hero(const Medium& medium, const Vec3f& o, const Vec3f& d, float tmax,
                                       int hero, Sampler& sampler, FlightRecord* record = nullptr);

} // namespace penumbra
