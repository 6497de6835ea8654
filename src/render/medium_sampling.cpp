#include "render/medium_sampling.h"

#include <cmath>

namespace penumbra {

namespace {

float channel(const Color3f& c, int i) { return i == 0 ? c.x : (i == 1 ? c.y : c.z); }
Color3f exp_neg(const Color3f& v) { return {std::exp(-v.x), std::exp(-v.y), std::exp(-v.z)}; }
float mean(const Color3f& c) { return (c.x + c.y + c.z) / 3.f; }

// Closed form: distance from channel c's exponential density, weight over the channel-averaged density.
FreeFlightSample sample_homogeneous(const Medium& medium, const Vec3f& o, const Vec3f& d, float tmax,
                                    Sampler& sampler) {
    FreeFlightSample s;
    const Color3f sigma_t = medium.sigma_t(o);
    const float u_channel = sampler.next_1d(), u = sampler.next_1d();
    const int c = std::min(int(u_channel * 3.f), 2);
    const float sc = channel(sigma_t, c);
    const float t = sc > 0.f ? -std::log1p(-u) / sc : Infinity;
    if (t < tmax) {
        const Vec3f p = o + d * t;
        const Color3f tr = exp_neg(sigma_t * t);
        s.pdf = sigma_t * tr;
        const float pdf = mean(s.pdf);
        if (!(pdf > 0.f)) return s; // cannot happen for a finite t; guards against underflow
        s.event = FreeFlightSample::Event::Scattered;
        s.t = t;
        s.p = p;
        s.weight = tr * (sigma_t * medium.albedo(p)) / pdf;
        return s;
    }
    const Color3f tr = std::isinf(tmax) ? Color3f(sigma_t.x > 0.f ? 0.f : 1.f, sigma_t.y > 0.f ? 0.f : 1.f,
                                                  sigma_t.z > 0.f ? 0.f : 1.f)
                                        : exp_neg(sigma_t * tmax);
    s.pdf = tr;
    const float pass = mean(tr);
    s.event = pass > 0.f ? FreeFlightSample::Event::Passed : FreeFlightSample::Event::Absorbed;
    s.weight = pass > 0.f ? tr / pass : Color3f(0.f);
    return s;
}

} // namespace

// Weighted delta tracking (Kutz et al. 2017, Eq. 9 with channel-averaged event probabilities): tentative
// collisions with the grey majorant m; at x the event is absorption, scattering or a null collision with
// probabilities mean(sigma_a)/m, mean(sigma_s)/m, mean(sigma_n)/m, sigma_n = m - sigma_t, and the weight is
// multiplied by sigma_event / (m P_event) per channel.
FreeFlightSample sample_free_flight(const Medium& medium, const Vec3f& o, const Vec3f& d, float tmax,
                                    Sampler& sampler, FlightRecord* record) {
    if (record) record->reset(tmax);
    if (medium.is_homogeneous()) return sample_homogeneous(medium, o, d, tmax, sampler);
    FreeFlightSample s;
    Color3f weight(1.f);
    bool done = false;
    for_each_tentative_collision(medium, o, d, tmax, sampler, [&](float t, const Vec3f& p, float m) {
        const Color3f sigma_t = medium.sigma_t(p);
        const Color3f sigma_s = sigma_t * medium.albedo(p);
        const Color3f sigma_a = sigma_t - sigma_s;
        const Color3f sigma_n = Color3f(m) - sigma_t;
        const float pa = std::max(mean(sigma_a), 0.f), ps = std::max(mean(sigma_s), 0.f),
                    pn = std::max(mean(sigma_n), 0.f);
        const float total = pa + ps + pn;
        const float u = sampler.next_1d() * total;
        if (u < pa) {
            s.event = FreeFlightSample::Event::Absorbed;
            done = true;
            return false;
        }
        if (u < pa + ps || !(pn > 0.f)) { // (the second test guards the rounding of u up to total)
            s.event = FreeFlightSample::Event::Scattered;
            s.t = t;
            s.p = p;
            s.weight = weight * sigma_s * (total / (m * ps));
            if (record) record->length = t, record->real_majorant = m, record->real_probability = ps / total;
            done = true;
            return false;
        }
        weight *= sigma_n * (total / (m * pn));
        if (record) record->collisions.push_back({t, m, pn / total});
        return true;
    });
    if (!done) {
        s.event = FreeFlightSample::Event::Passed;
        s.weight = weight;
    }
    return s;
}

// Ratio tracking (Novák et al. 2014): the product of (1 - sigma_t/m) over tentative collisions, with Russian
// roulette once every channel's running estimate is below 0.1 (unbiased: survivors are divided by the
// survival probability).
Color3f transmittance(const Medium& medium, const Vec3f& o, const Vec3f& d, float tmax, Sampler& sampler,
                      FlightRecord* record) {
    if (record) record->reset(tmax);
    if (medium.is_homogeneous()) {
        const Color3f sigma_t = medium.sigma_t(o);
        if (std::isinf(tmax))
            return {sigma_t.x > 0.f ? 0.f : 1.f, sigma_t.y > 0.f ? 0.f : 1.f, sigma_t.z > 0.f ? 0.f : 1.f};
        return exp_neg(sigma_t * tmax);
    }
    Color3f tr(1.f);
    for_each_tentative_collision(medium, o, d, tmax, sampler, [&](float t, const Vec3f& p, float m) {
        tr *= Color3f(1.f) - medium.sigma_t(p) / m;
        const float q = max_component(tr);
        float survival = 1.f;
        if (q < 0.1f) {
            if (!(q > 0.f) || sampler.next_1d() >= q) {
                tr = Color3f(0.f);
                return false;
            }
            tr /= q;
            survival = q;
        }
        if (record) record->collisions.push_back({t, m, survival});
        return true;
    });
    return tr;
}

float free_flight_pdf(const Medium& medium, const Vec3f& o, const Vec3f& d, float t, bool scattered) {
    if (medium.is_homogeneous()) {
        const Color3f sigma_t = medium.sigma_t(o);
        const Color3f tr = std::isinf(t) ? Color3f(sigma_t.x > 0.f ? 0.f : 1.f, sigma_t.y > 0.f ? 0.f : 1.f,
                                                   sigma_t.z > 0.f ? 0.f : 1.f)
                                         : exp_neg(sigma_t * t);
        return mean(scattered ? sigma_t * tr : tr);
    }
    // Midpoint rule on every segment where the medium may be non-zero (16 steps each).
    constexpr int steps = 16;
    float optical_depth = 0.f;
    medium.majorants(o, d, 0.f, t, [&](float t0, float t1, float m) {
        if (!(m > 0.f)) return true;
        if (std::isinf(t1)) {
            optical_depth = Infinity;
            return false;
        }
        const float h = (t1 - t0) / steps;
        for (int i = 0; i < steps; ++i)
            optical_depth += mean(medium.sigma_t(o + d * (t0 + (i + 0.5f) * h))) * h;
        return true;
    });
    const float tr = std::exp(-optical_depth);
    return scattered ? mean(medium.sigma_t(o + d * t)) * tr : tr;
}

} // namespace penumbra
