// Small fixed-size vectors templated on the scalar type (float for rendering, AD types for derivatives).
#pragma once
#include "core/math.h"

#include <ostream>

namespace penumbra {

template <typename T> struct Vec2 {
    T x{}, y{};
    Vec2() = default;
    Vec2(T x, T y) : x(x), y(y) {}
    explicit Vec2(T v) : x(v), y(v) {}
    template <typename U> explicit Vec2(const Vec2<U>& o) : x(T(o.x)), y(T(o.y)) {}
    T& operator[](int i) { return i == 0 ? x : y; }
    const T& operator[](int i) const { return i == 0 ? x : y; }
    Vec2 operator+(const Vec2& o) const { return {x + o.x, y + o.y}; }
    Vec2 operator-(const Vec2& o) const { return {x - o.x, y - o.y}; }
    Vec2 operator*(const Vec2& o) const { return {x * o.x, y * o.y}; }
    Vec2 operator*(const T& s) const { return {x * s, y * s}; }
    Vec2 operator/(const T& s) const { return {x / s, y / s}; }
    Vec2& operator+=(const Vec2& o) { x += o.x; y += o.y; return *this; }
    bool operator==(const Vec2& o) const { return x == o.x && y == o.y; }
};

template <typename T> struct Vec3 {
    T x{}, y{}, z{};
    Vec3() = default;
    Vec3(T x, T y, T z) : x(x), y(y), z(z) {}
    explicit Vec3(T v) : x(v), y(v), z(v) {}
    template <typename U> explicit Vec3(const Vec3<U>& o) : x(T(o.x)), y(T(o.y)), z(T(o.z)) {}
    T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    const T& operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    Vec3 operator-() const { return {-x, -y, -z}; }
    Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
    Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
    // Component-wise product: colors are Vec3 too.
    Vec3 operator*(const Vec3& o) const { return {x * o.x, y * o.y, z * o.z}; }
    Vec3 operator/(const Vec3& o) const { return {x / o.x, y / o.y, z / o.z}; }
    Vec3 operator*(const T& s) const { return {x * s, y * s, z * s}; }
    Vec3 operator/(const T& s) const { return {x / s, y / s, z / s}; }
    Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
    Vec3& operator-=(const Vec3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
    Vec3& operator*=(const Vec3& o) { x *= o.x; y *= o.y; z *= o.z; return *this; }
    Vec3& operator*=(const T& s) { x *= s; y *= s; z *= s; return *this; }
    Vec3& operator/=(const T& s) { x /= s; y /= s; z /= s; return *this; }
    bool operator==(const Vec3& o) const { return x == o.x && y == o.y && z == o.z; }
    bool operator!=(const Vec3& o) const { return !(*this == o); }
};

template <typename T> inline Vec3<T> operator*(const T& s, const Vec3<T>& v) { return v * s; }
template <typename T> inline Vec2<T> operator*(const T& s, const Vec2<T>& v) { return v * s; }

template <typename T> inline T dot(const Vec3<T>& a, const Vec3<T>& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <typename T> inline T absdot(const Vec3<T>& a, const Vec3<T>& b) {
    using std::abs;
    return abs(dot(a, b));
}
template <typename T> inline Vec3<T> cross(const Vec3<T>& a, const Vec3<T>& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename T> inline T squared_norm(const Vec3<T>& v) { return dot(v, v); }
template <typename T> inline T norm(const Vec3<T>& v) {
    using std::sqrt;
    return sqrt(dot(v, v));
}
template <typename T> inline Vec3<T> normalize(const Vec3<T>& v) { return v / norm(v); }
template <typename T> inline Vec3<T> abs(const Vec3<T>& v) {
    using std::abs;
    return {abs(v.x), abs(v.y), abs(v.z)};
}
template <typename T> inline Vec3<T> min(const Vec3<T>& a, const Vec3<T>& b) {
    using std::min;
    return {min(a.x, b.x), min(a.y, b.y), min(a.z, b.z)};
}
template <typename T> inline Vec3<T> max(const Vec3<T>& a, const Vec3<T>& b) {
    using std::max;
    return {max(a.x, b.x), max(a.y, b.y), max(a.z, b.z)};
}
template <typename T> inline T max_component(const Vec3<T>& v) {
    using std::max;
    return max(v.x, max(v.y, v.z));
}
template <typename T> inline T min_component(const Vec3<T>& v) {
    using std::min;
    return min(v.x, min(v.y, v.z));
}
template <typename T> inline Vec3<T> lerp(float t, const Vec3<T>& a, const Vec3<T>& b) { return a * T(1.f - t) + b * T(t); }
// Reflect wi about n (both pointing away from the surface).
template <typename T> inline Vec3<T> reflect(const Vec3<T>& wi, const Vec3<T>& n) { return n * (T(2) * dot(wi, n)) - wi; }

using Vec2f = Vec2<float>;
using Vec2i = Vec2<int>;
using Vec3f = Vec3<float>;
using Vec3d = Vec3<double>;
using Vec3i = Vec3<int>;
// Colors are linear-sRGB triples.
template <typename T> using Color3 = Vec3<T>;
using Color3f = Color3<float>;

template <typename T> inline T luminance(const Color3<T>& c) {
    return c.x * 0.212671f + c.y * 0.715160f + c.z * 0.072169f;
}
inline bool is_black(const Color3f& c) { return c.x == 0.f && c.y == 0.f && c.z == 0.f; }
inline bool is_finite(const Vec3f& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
inline Vec3f detach(const Vec3f& v) { return v; }

template <typename T> std::ostream& operator<<(std::ostream& os, const Vec3<T>& v) {
    return os << "[" << v.x << ", " << v.y << ", " << v.z << "]";
}
template <typename T> std::ostream& operator<<(std::ostream& os, const Vec2<T>& v) {
    return os << "[" << v.x << ", " << v.y << "]";
}

} // namespace penumbra
