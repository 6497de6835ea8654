// Scalar helpers shared by all code, templated so that AD scalar types pass through.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace penumbra {

constexpr float Pi = 3.14159265358979323846f;
constexpr float InvPi = 1.f / Pi;
constexpr float Inv2Pi = 0.5f / Pi;
constexpr float Inv4Pi = 0.25f / Pi;
constexpr float Infinity = std::numeric_limits<float>::infinity();
// Offset used when spawning rays, relative to the magnitude of the origin.
constexpr float RayEpsilon = 1e-4f;

template <typename T> inline T sqr(const T& x) { return x * x; }
template <typename T> inline T safe_sqrt(const T& x) {
    using std::sqrt;
    return x > T(0) ? sqrt(x) : T(0);
}
template <typename T> inline T clamp(const T& x, float lo, float hi) {
    return x < T(lo) ? T(lo) : (x > T(hi) ? T(hi) : x);
}
template <typename T> inline T lerp(float t, const T& a, const T& b) { return a * (1.f - t) + b * t; }
inline float radians(float deg) { return deg * (Pi / 180.f); }
inline float degrees(float rad) { return rad * (180.f / Pi); }
// Strip any derivative information (identity for plain floats; AD types overload this).
inline float detach(float x) { return x; }

} // namespace penumbra
