// Anisotropic Beckmann and GGX microfacet distributions (Walter et al. 2007; Heitz 2014 for Smith masking),
// with visible-normal sampling: Heitz 2018 for GGX, Jakob 2014's inversion of the Beckmann visible-slope
// CDF (Mitsuba 3's scheme). D, G1, G and pdf are templated on the scalar type; sampling is float only.
#pragma once
#include "core/frame.h"
#include "core/fresnel.h"
#include "core/quadrature.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

enum class MicrofacetType { Beckmann, GGX };

// Inverse error function: Giles' single-precision approximation refined by two Newton steps in double.
inline float erfinv(float y) {
    float w = -std::log((1.f - y) * (1.f + y)), p;
    if (w < 5.f) {
        w -= 2.5f;
        p = 2.81022636e-08f;
        p = 3.43273939e-07f + p * w;
        p = -3.5233877e-06f + p * w;
        p = -4.39150654e-06f + p * w;
        p = 0.00021858087f + p * w;
        p = -0.00125372503f + p * w;
        p = -0.00417768164f + p * w;
        p = 0.246640727f + p * w;
        p = 1.50140941f + p * w;
    } else {
        w = std::sqrt(w) - 3.f;
        p = -0.000200214257f;
        p = 0.000100950558f + p * w;
        p = 0.00134934322f + p * w;
        p = -0.00367342844f + p * w;
        p = 0.00573950773f + p * w;
        p = -0.0076224613f + p * w;
        p = 0.00943887047f + p * w;
        p = 1.00167406f + p * w;
        p = 2.83297682f + p * w;
    }
    double x = double(p) * y;
    if (!std::isfinite(x)) return float(x);
    for (int i = 0; i < 2; ++i) {
        const double d = 1.1283791670955126 * std::exp(-x * x); // d erf / dx = 2/sqrt(pi) exp(-x^2)
        if (d <= 1e-300) break;
        x -= (std::erf(x) - double(y)) / d;
    }
    return float(x);
}

template <typename T> struct MicrofacetDistribution {
    MicrofacetType type = MicrofacetType::Beckmann;
    T alpha_u = T(0.1f), alpha_v = T(0.1f);
    bool sample_visible = true;

    // The roughnesses in use: clamped to at least 1e-4 as Mitsuba's MicrofacetDistribution::configure() does
    // (a zero roughness, e.g. from a texture, behaves as a very smooth surface instead of dividing by zero).
    T au() const { return alpha_u < T(MinAlpha) ? T(MinAlpha) : alpha_u; }
    T av() const { return alpha_v < T(MinAlpha) ? T(MinAlpha) : alpha_v; }
    static constexpr float MinAlpha = 1e-4f;

    // Normal distribution D(m) for m in the upper hemisphere, normalized so that int D(m) cos(theta_m) dm = 1:
    //   Beckmann: exp(-(m_x^2/au^2 + m_y^2/av^2) / m_z^2) / (pi au av m_z^4)
    //   GGX:      1 / (pi au av (m_x^2/au^2 + m_y^2/av^2 + m_z^2)^2)
    T D(const Vec3<T>& m) const {
        using std::exp;
        if (!(m.z > T(0))) return T(0);
        const T c2 = m.z * m.z;
        const T r = sqr(m.x / au()) + sqr(m.y / av());
        if (type == MicrofacetType::Beckmann) return exp(-r / c2) / (T(Pi) * au() * av() * c2 * c2);
        return T(1) / (T(Pi) * au() * av() * sqr(r + c2));
    }

    // Smith's monodirectional masking G1(v, m) (zero when v sees the back of m):
    //   GGX: 2 / (1 + sqrt(1 + a^2 tan^2)),  Beckmann: Walter et al.'s rational fit in a = 1 / (alpha tan).
    T G1(const Vec3<T>& v, const Vec3<T>& m) const {
        using std::sqrt;
        if (!(dot(v, m) * v.z > T(0))) return T(0);
        const T xy = sqr(au() * v.x) + sqr(av() * v.y);
        if (xy == T(0)) return T(1);
        const T tan2 = xy / (v.z * v.z);
        if (type == MicrofacetType::Beckmann) {
            const T a = T(1) / sqrt(tan2);
            if (a >= T(1.6f)) return T(1);
            return (T(3.535f) * a + T(2.181f) * a * a) / (T(1) + T(2.276f) * a + T(2.577f) * a * a);
        }
        return T(2) / (T(1) + sqrt(T(1) + tan2));
    }

    // Separable shadowing-masking G = G1(wi, m) G1(wo, m).
    T G(const Vec3<T>& wi, const Vec3<T>& wo, const Vec3<T>& m) const { return G1(wi, m) * G1(wo, m); }

    // Solid-angle density of the normals drawn by sample(): visible normals D_wi(m) = G1(wi,m) |wi.m| D(m) / wi.z,
    // otherwise D(m) m_z. Expects wi.z > 0.
    T pdf(const Vec3<T>& wi, const Vec3<T>& m) const {
        using std::abs;
        if (sample_visible) return D(m) * G1(wi, m) * abs(dot(wi, m)) / wi.z;
        return D(m) * m.z;
    }

    // Samples a microfacet normal (float only). Expects wi.z > 0 when sampling visible normals.
    Vec3<T> sample(const Vec3<T>& wi, const Vec2f& u) const {
        if (!sample_visible) return sample_all(u);
        // Stretch to the configuration alpha = 1, sample the visible slopes there, unstretch.
        const Vec3f wi_s = normalize(Vec3f(au() * wi.x, av() * wi.y, wi.z));
        if (type == MicrofacetType::GGX) {
            // Heitz 2018, "Sampling the GGX Distribution of Visible Normals": uniform point on the projected
            // hemisphere seen from wi_s.
            const float lensq = wi_s.x * wi_s.x + wi_s.y * wi_s.y;
            const Vec3f t1 = lensq > 0.f ? Vec3f(-wi_s.y, wi_s.x, 0.f) / std::sqrt(lensq) : Vec3f(1.f, 0.f, 0.f);
            const Vec3f t2 = cross(wi_s, t1);
            const float r = std::sqrt(u.x), phi = 2.f * Pi * u.y;
            const float p1 = r * std::cos(phi);
            float p2 = r * std::sin(phi);
            const float s = 0.5f * (1.f + wi_s.z);
            p2 = (1.f - s) * std::sqrt(std::max(0.f, 1.f - p1 * p1)) + s * p2;
            const Vec3f nh = t1 * p1 + t2 * p2 + wi_s * std::sqrt(std::max(0.f, 1.f - p1 * p1 - p2 * p2));
            return normalize(Vec3f(au() * nh.x, av() * nh.y, std::max(1e-7f, nh.z)));
        }
        const float sin_phi_len = std::sqrt(wi_s.x * wi_s.x + wi_s.y * wi_s.y);
        const float cos_phi = sin_phi_len > 0.f ? wi_s.x / sin_phi_len : 1.f;
        const float sin_phi = sin_phi_len > 0.f ? wi_s.y / sin_phi_len : 0.f;
        Vec2f slope = beckmann_visible_slopes_11(wi_s.z, u);
        // Rotate from the incidence plane back to the local frame and unstretch.
        slope = Vec2f(cos_phi * slope.x - sin_phi * slope.y, sin_phi * slope.x + cos_phi * slope.y);
        return normalize(Vec3f(-slope.x * au(), -slope.y * av(), 1.f));
    }

private:
    // Sampling proportional to D(m) cos(theta_m): tan^2(theta) = -a^2 log(1-u) (Beckmann), a^2 u / (1-u) (GGX),
    // with the anisotropic azimuth tan(phi) = (av/au) tan(2 pi u) and a^2 = 1 / (cos^2 phi/au^2 + sin^2 phi/av^2).
    Vec3f sample_all(const Vec2f& u) const {
        float phi = std::atan(av() / au() * std::tan(Pi + 2.f * Pi * u.y)) + Pi * std::floor(2.f * u.y + 0.5f);
        const float cp = std::cos(phi), sp = std::sin(phi);
        const float a2 = 1.f / (sqr(cp / au()) + sqr(sp / av()));
        const float tan2 = type == MicrofacetType::Beckmann ? -a2 * std::log1p(-u.x) : a2 * u.x / (1.f - u.x);
        const float cos_theta = 1.f / std::sqrt(1.f + tan2);
        const float sin_theta = std::sqrt(std::max(0.f, 1.f - cos_theta * cos_theta));
        return {sin_theta * cp, sin_theta * sp, cos_theta};
    }

    // Visible slopes of the unit Beckmann distribution for incidence cos(theta_i), in the incidence plane
    // (Jakob 2014, "An Improved Visible Normal Sampling Routine for the Beckmann Distribution"): Newton-bisection
    // inversion of the marginal CDF of slope_x, then slope_y from the Gaussian conditional.
    static Vec2f beckmann_visible_slopes_11(float cos_theta_i, const Vec2f& u) {
        constexpr double inv_sqrt_pi = 0.56418958354775628;
        if (cos_theta_i > 0.99999f) {
            const float r = std::sqrt(-std::log1p(-u.x)), phi = 2.f * Pi * u.y;
            return {r * std::cos(phi), r * std::sin(phi)};
        }
        const double ct = cos_theta_i, st = std::sqrt(std::max(0.0, 1.0 - ct * ct));
        const double tan_t = st / ct, cot_t = ct / st;
        // Marginal CDF of the visible slope x: C(x) = (1 + erf(x) + tan_t exp(-x^2)/sqrt(pi)) / norm, as a function of b = erf(x).
        double a = -1.0, c = std::erf(cot_t);
        const double sample_x = std::max(double(u.x), 1e-6);
        const double theta = std::acos(ct);
        const double fit = 1.0 + theta * (-0.876 + theta * (0.4265 - 0.0594 * theta));
        double b = c - (1.0 + c) * std::pow(1.0 - sample_x, fit);
        const double norm = 1.0 / (1.0 + c + inv_sqrt_pi * tan_t * std::exp(-cot_t * cot_t));
        for (int it = 0; it < 20; ++it) {
            if (!(b >= a && b <= c)) b = 0.5 * (a + c);
            const double x = erfinv(float(b));
            const double value = norm * (1.0 + b + inv_sqrt_pi * tan_t * std::exp(-x * x)) - sample_x;
            const double deriv = norm * (1.0 - x * tan_t);
            if (std::abs(value) < 1e-6) break;
            if (value > 0.0) c = b;
            else a = b;
            b -= value / deriv;
        }
        return {erfinv(float(b)), erfinv(float(2.0 * std::max(double(u.y), 1e-6) - 1.0))};
    }
};

// Directional albedos of a rough dielectric interface (relative IOR eta) lit from wi (wi.z > 0), as Mitsuba's
// eval_reflectance / eval_transmittance tabulate them: expectations over visible normals m ~ D_wi of
//   reflection:   F(wi.m) G1(wo, m),        wo = reflect(wi, m)        (zero unless wo.z > 0)
//   transmission: (1 - F(wi.m)) G1(wo, m),  wo = refract(wi, m)        (zero unless wo.z < 0)
// by an n x n Gauss-Legendre rule on the sampling square (n = 32 for eta > 1, else 128: total internal
// reflection makes the integrand rougher). 1 - reflection != transmission: masking of the outgoing
// direction removes energy from both.
enum class InterfaceLobe { Reflection, Transmission };
inline float rough_interface_albedo(MicrofacetDistribution<float> distr, const Vec3f& wi, float eta,
                                    InterfaceLobe lobe) {
    distr.sample_visible = true;
    const int n = eta > 1.f ? 32 : 128;
    std::vector<double> nodes, weights;
    gauss_legendre(n, nodes, weights);
    double sum = 0.0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const Vec2f u(float(0.5 * nodes[j] + 0.5), float(0.5 * nodes[i] + 0.5));
            const Vec3f m = distr.sample(wi, u);
            const FresnelDielectric<float> f = fresnel_dielectric(dot(wi, m), eta);
            float value;
            if (lobe == InterfaceLobe::Reflection) {
                const Vec3f wo = reflect(wi, m);
                value = wo.z > 0.f ? f.F * distr.G1(wo, m) : 0.f;
            } else {
                const Vec3f wo = refract(wi, m, f.cos_theta_t, f.eta_ti);
                value = wo.z < 0.f ? (1.f - f.F) * distr.G1(wo, m) : 0.f;
            }
            sum += 0.25 * weights[i] * weights[j] * value;
        }
    return float(sum);
}

// Differential microfacet sampling (paper 002 §4.1, after Zeltner et al. 2021): the positivization of
// ∂D/∂α(m) cos θ_m for an isotropic roughness α. With s = tan²θ_m / α², the derivative changes sign at s = 1
// (negative below for both distributions) and each part carries the same mass, so each is normalized on its
// own (densities in s, Beckmann: e |1 − s| e^{−s}; GGX: 4 |s − 1| / (1 + s)³) and sampled by inverting its
// CDF: in closed form for GGX, by the two branches of the Lambert W function (Newton iterations) for
// Beckmann. Sampling-only (float): the derivative itself always comes from D() with Var.
struct DifferentialNDF {
    MicrofacetType type = MicrofacetType::Beckmann;
    float alpha = 0.1f;

    // A microfacet normal from the positive (sign > 0: s >= 1) or negative (sign < 0: s <= 1) part.
    Vec3f sample(int sign, const Vec2f& u) const {
        const double xi = std::min(double(u.x), 1.0 - 1e-7);
        double s;
        if (type == MicrofacetType::GGX) {
            // CDF−(s) = 4s/(1+s)², CDF+(s) = (2y − 1)² with y = 1/(1+s).
            const double y = sign < 0 ? 0.5 * (1.0 + std::sqrt(1.0 - xi)) : 0.5 * (1.0 - std::sqrt(xi));
            s = (1.0 - y) / y;
        } else {
            // CDF−(s) = e s e^{−s} (s <= 1), CDF+(s) = 1 − e s e^{−s} (s >= 1): solve s e^{−s} = c.
            constexpr double inv_e = 0.36787944117144233;
            s = solve_s_exp_minus_s(sign < 0 ? xi * inv_e : (1.0 - xi) * inv_e, sign > 0);
        }
        const double tan2 = double(alpha) * alpha * s;
        const double cos_theta = 1.0 / std::sqrt(1.0 + tan2);
        const double sin_theta = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
        const double phi = 2.0 * Pi * u.y;
        return {float(sin_theta * std::cos(phi)), float(sin_theta * std::sin(phi)), float(cos_theta)};
    }

    // Solid-angle density of sample(sign, ·) at m: p_s(s) / (π α² cos³θ_m).
    float pdf(int sign, const Vec3f& m) const {
        if (!(m.z > 0.f)) return 0.f;
        const double c2 = double(m.z) * m.z;
        const double s = std::max(0.0, 1.0 - c2) / (c2 * alpha * alpha);
        if ((sign < 0 && s > 1.0) || (sign > 0 && s < 1.0)) return 0.f;
        const double p_s = type == MicrofacetType::GGX ? 4.0 * std::abs(s - 1.0) / ((1.0 + s) * (1.0 + s) * (1.0 + s))
                                                       : 2.718281828459045 * std::abs(1.0 - s) * std::exp(-s);
        return float(p_s / (Pi * double(alpha) * alpha * c2 * m.z));
    }

private:
    // The root of s e^{−s} = c (0 <= c <= 1/e) on [0, 1] (−W₀(−c)) or on [1, ∞) (−W₋₁(−c)): Newton's method on
    // log s − s − log c, safeguarded by bisection.
    static double solve_s_exp_minus_s(double c, bool upper) {
        if (c <= 0.0) return upper ? 1e30 : 0.0;
        c = std::min(c, 0.36787944117144233);
        const double log_c = std::log(c);
        double lo = upper ? 1.0 : 0.0, hi = upper ? 2.0 - 2.0 * log_c : 1.0;
        double s = upper ? std::max(1.0, -log_c + std::log(std::max(1.0, -log_c))) : c * (1.0 + c);
        for (int it = 0; it < 100; ++it) {
            const double g = std::log(s) - s - log_c; // increasing on (0, 1), decreasing on (1, ∞)
            if ((g < 0.0) != upper) lo = s;
            else hi = s;
            const double dg = 1.0 / s - 1.0;
            double next = s - g / dg;
            if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
            if (std::abs(next - s) <= 1e-13 * std::max(1.0, s)) return next;
            s = next;
        }
        return s;
    }
};

} // namespace penumbra
