#include "render/hero_free_flight.h"

#include <cmath>

namespace penumbra {

namespace {

Color3f exp_neg(const Color3f& v) { return {std::exp(-v.x), std::exp(-v.y), std::exp(-v.z)}; }

// Transmittance over an infinite distance: 0 where sigma_t > 0, else 1.
Color3f infinite_transmittance(const Color3f& sigma_t) {
    return {sigma_t.x > 0.f ? 0.f : 1.f, sigma_t.y > 0.f ? 0.f : 1.f, sigma_t.z > 0.f ? 0.f : 1.f};
}

HeroFreeFlight sample_homogeneous(const Medium& medium, const Vec3f& o, const Vec3f& d, float tmax, int hero,
                                  Sampler& sampler, FlightRecord* record) {
    HeroFreeFlight s;
    const Color3f sigma_t = medium.sigma_t(o);
    const float sc = sigma_t[hero];
    const float t = sc > 0.f ? -std::log1p(-sampler.next_1d()) / sc : Infinity;
    if (t < tmax) {
        // Density of scattering at t under channel i: sigma_t,i Tr_i(t); the integrand has sigma_s Tr(t).
        const Color3f tr = exp_neg(sigma_t * t);
        const float pdf = sc * tr[hero];
        if (!(pdf > 0.f)) { // underflow far beyond the mean free path: no channel can be continued
            s.event = FreeFlightSample::Event::Absorbed;
            s.weight = Color3f(0.f);
            return s;
        }
        s.event = FreeFlightSample::Event::Scattered;
        s.t = t;
        s.p = o + d * t;
        s.weight = tr * sigma_t * medium.albedo(s.p) / pdf;
        s.ratio = tr * sigma_t / pdf;
        if (record) record->reset(t), record->pdf = pdf;
        return s;
    }
    // Passing the segment: probability Tr_i(tmax) under channel i, the integrand has Tr(tmax). Tr_c > 0 here.
    const Color3f tr = std::isinf(tmax) ? infinite_transmittance(sigma_t) : exp_neg(sigma_t * tmax);
    s.weight = s.ratio = tr / tr[hero];
    if (record) record->reset(tmax), record->pdf = tr[hero];
    return s;
}

} // namespace

HeroFreeFlight sample_free_flight_hero(const Medium& medium, const Vec3f& o, const Vec3f& d, float tmax,
                                       int hero, Sampler& sampler, FlightRecord* record) {
    if (medium.is_homogeneous()) return sample_homogeneous(medium, o, d, tmax, hero, sampler, record);
    HeroFreeFlight s;
    if (record) record->reset(tmax);
    for_each_tentative_collision(medium, o, d, tmax, sampler, [&](float t, const Vec3f& p, float m) {
        const Color3f sigma_t = medium.sigma_t(p);
        const Color3f sigma_s = sigma_t * medium.albedo(p);
        const Color3f sigma_a = sigma_t - sigma_s;
        const Color3f sigma_n(std::max(m - sigma_t.x, 0.f), std::max(m - sigma_t.y, 0.f),
                              std::max(m - sigma_t.z, 0.f));
        const float u = sampler.next_1d() * m;
        if (u < sigma_a[hero]) {
            s.event = FreeFlightSample::Event::Absorbed;
            s.weight = Color3f(0.f);
            return false;
        }
        if (u < sigma_a[hero] + sigma_s[hero]) {
            s.event = FreeFlightSample::Event::Scattered;
            s.t = t;
            s.p = p;
            s.weight *= sigma_s / sigma_s[hero];
            s.ratio *= sigma_s / sigma_s[hero];
            if (record) record->length = t, record->real_majorant = m, record->real_probability = sigma_s[hero] / m;
            return false;
        }
        if (!(sigma_n[hero] > 0.f)) { // rounding put u past sigma_t,c = m: treat as absorbed
            s.event = FreeFlightSample::Event::Absorbed;
            s.weight = Color3f(0.f);
            return false;
        }
        s.weight *= sigma_n / sigma_n[hero];
        s.ratio *= sigma_n / sigma_n[hero];
        if (record) record->collisions.push_back({t, m, sigma_n[hero] / m});
        return true;
    });
    return s;
}

} // namespace penumbra
