// Fresnel equations for unpolarized light (Mitsuba 3 conventions), templated on the scalar type.
#pragma once
#include "core/vector.h"

namespace penumbra {

// Result of the dielectric Fresnel equations at an interface with relative IOR eta = eta_int / eta_ext.
template <typename T> struct FresnelDielectric {
    T F;           // reflectance
    T cos_theta_t; // cosine of the refracted direction, with the sign opposite to cos_theta_i
    T eta_it;      // relative IOR eta_i / eta_t along the incident side
    T eta_ti;      // its reciprocal (scales the tangential component on refraction)
};

// Dielectric Fresnel reflectance F = (r_s^2 + r_p^2) / 2 with
//   r_s = (cos_i - eta_it cos_t) / (cos_i + eta_it cos_t),  r_p = (eta_it cos_i - cos_t) / (eta_it cos_i + cos_t).
// cos_theta_i < 0 means the incident direction is inside (the IOR ratio is inverted). Total internal
// reflection gives F = 1 and cos_theta_t = 0; an index-matched interface gives F = 0.
// `eta` is a float, or T when the IOR itself is differentiated.
template <typename T, typename E = float> FresnelDielectric<T> fresnel_dielectric(const T& cos_theta_i, const E& eta) {
    using std::abs;
    const bool outside = cos_theta_i >= T(0);
    const T eta_it = outside ? T(eta) : T(1.f) / T(eta), eta_ti = outside ? T(1.f) / T(eta) : T(eta);
    // Snell's law: sin_t^2 = eta_ti^2 sin_i^2.
    const T cos_t2 = T(1) - (T(1) - cos_theta_i * cos_theta_i) * (eta_ti * eta_ti);
    const T ci = abs(cos_theta_i);
    const T ct = safe_sqrt(cos_t2);
    T F;
    if (detach(eta) == 1.f)
        F = T(0);
    else if (ci == T(0))
        F = T(1);
    else {
        const T a_s = (ci - T(eta_it) * ct) / (ci + T(eta_it) * ct);
        const T a_p = (T(eta_it) * ci - ct) / (T(eta_it) * ci + ct);
        F = T(0.5f) * (a_s * a_s + a_p * a_p);
    }
    return {F, outside ? -ct : ct, eta_it, eta_ti};
}

// Conductor Fresnel reflectance for a complex relative IOR eta + i k (exact; Born & Wolf), with
// a^2 + b^2 = sqrt((eta^2 - k^2 - sin^2)^2 + 4 eta^2 k^2) and a = sqrt((a^2 + b^2 + eta^2 - k^2 - sin^2) / 2):
//   R_s = (a^2+b^2 + cos^2 - 2 a cos) / (a^2+b^2 + cos^2 + 2 a cos)
//   R_p = R_s ((a^2+b^2) cos^2 + sin^4 - 2 a cos sin^2) / ((a^2+b^2) cos^2 + sin^4 + 2 a cos sin^2).
template <typename T> T fresnel_conductor(const T& cos_theta_i, const T& eta, const T& k) {
    const T c2 = cos_theta_i * cos_theta_i;
    const T s2 = T(1) - c2;
    const T s4 = s2 * s2;
    const T t1 = eta * eta - k * k - s2;
    const T a2pb2 = safe_sqrt(t1 * t1 + T(4) * eta * eta * k * k);
    const T a = safe_sqrt(T(0.5f) * (a2pb2 + t1));
    const T term1 = a2pb2 + c2, term2 = T(2) * cos_theta_i * a;
    const T Rs = (term1 - term2) / (term1 + term2);
    const T term3 = a2pb2 * c2 + s4, term4 = term2 * s2;
    const T Rp = Rs * (term3 - term4) / (term3 + term4);
    return T(0.5f) * (Rs + Rp);
}
template <typename T> Color3<T> fresnel_conductor(const T& cos_theta_i, const Color3<T>& eta, const Color3<T>& k) {
    return {fresnel_conductor(cos_theta_i, eta.x, k.x), fresnel_conductor(cos_theta_i, eta.y, k.y),
            fresnel_conductor(cos_theta_i, eta.z, k.z)};
}

// Refraction of wi about the normal m given the Fresnel quantities (Mitsuba's convention: the result
// points away from the surface on the other side): wo = m (dot(wi, m) eta_ti + cos_theta_t) - wi eta_ti.
template <typename T>
Vec3<T> refract(const Vec3<T>& wi, const Vec3<T>& m, const T& cos_theta_t, const T& eta_ti) {
    return m * (dot(wi, m) * eta_ti + cos_theta_t) - wi * eta_ti;
}

// Hemispherical average of the dielectric reflectance, Fdr = 2 * int_0^1 F(mu) mu dmu (numerical quadrature;
// the internal diffuse reflectance used by `plastic`).
inline float fresnel_diffuse_reflectance(float eta) {
    // Midpoint rule on 4096 intervals: the integrand is smooth except for the total-reflection kink (eta < 1),
    // so the error is far below the 1e-3 accuracy of the polynomial fits Mitsuba uses.
    constexpr int n = 4096;
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
        const float mu = (i + 0.5f) / n;
        sum += double(fresnel_dielectric(mu, eta).F) * mu;
    }
    return float(2.0 * sum / n);
}

} // namespace penumbra
