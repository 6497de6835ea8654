// Warping functions from the unit square to common domains, with their densities.
#pragma once
#include "core/vector.h"

namespace penumbra::warp {

// Concentric mapping (Shirley & Chiu 1997) to the unit disk; density 1/pi.
inline Vec2f square_to_uniform_disk_concentric(const Vec2f& u) {
    const float x = 2.f * u.x - 1.f, y = 2.f * u.y - 1.f;
    if (x == 0.f && y == 0.f) return {0.f, 0.f};
    float r, phi;
    if (std::abs(x) > std::abs(y)) {
        r = x;
        phi = (Pi / 4.f) * (y / x);
    } else {
        r = y;
        phi = (Pi / 2.f) - (Pi / 4.f) * (x / y);
    }
    return {r * std::cos(phi), r * std::sin(phi)};
}

inline Vec3f square_to_cosine_hemisphere(const Vec2f& u) {
    const Vec2f d = square_to_uniform_disk_concentric(u);
    const float z = std::sqrt(std::max(0.f, 1.f - d.x * d.x - d.y * d.y));
    return {d.x, d.y, z};
}
template <typename T> inline T square_to_cosine_hemisphere_pdf(const Vec3<T>& v) {
    return v.z > T(0) ? v.z * T(InvPi) : T(0);
}

inline Vec3f square_to_uniform_sphere(const Vec2f& u) {
    const float z = 1.f - 2.f * u.y;
    const float r = std::sqrt(std::max(0.f, 1.f - z * z));
    const float phi = 2.f * Pi * u.x;
    return {r * std::cos(phi), r * std::sin(phi), z};
}
constexpr float square_to_uniform_sphere_pdf() { return Inv4Pi; }

inline Vec3f square_to_uniform_hemisphere(const Vec2f& u) {
    const float z = u.y;
    const float r = std::sqrt(std::max(0.f, 1.f - z * z));
    const float phi = 2.f * Pi * u.x;
    return {r * std::cos(phi), r * std::sin(phi), z};
}
constexpr float square_to_uniform_hemisphere_pdf() { return Inv2Pi; }

// Uniform direction inside a cone around +z with the given cos(theta_max).
inline Vec3f square_to_uniform_cone(const Vec2f& u, float cos_cutoff) {
    const float cos_theta = (1.f - u.y) + u.y * cos_cutoff;
    const float sin_theta = std::sqrt(std::max(0.f, 1.f - cos_theta * cos_theta));
    const float phi = 2.f * Pi * u.x;
    return {sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta};
}
inline float square_to_uniform_cone_pdf(float cos_cutoff) { return 1.f / (2.f * Pi * (1.f - cos_cutoff)); }

// Uniform barycentrics (b1, b2) on a triangle (Heitz 2019 low-distortion map is not needed here).
inline Vec2f square_to_uniform_triangle(const Vec2f& u) {
    const float t = std::sqrt(1.f - u.x);
    return {1.f - t, t * u.y};
}

} // namespace penumbra::warp
