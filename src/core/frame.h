// Orthonormal shading frames (local z = normal).
#pragma once
#include "core/vector.h"

namespace penumbra {

// Branchless orthonormal basis from a unit vector (Duff et al. 2017, "Building an Orthonormal Basis, Revisited").
template <typename T> inline void coordinate_system(const Vec3<T>& n, Vec3<T>& s, Vec3<T>& t) {
    using std::copysign;
    const float sign = std::copysign(1.f, detach(n.z));
    const T a = T(-1.f) / (T(sign) + n.z);
    const T b = n.x * n.y * a;
    s = Vec3<T>(T(1.f) + T(sign) * n.x * n.x * a, T(sign) * b, T(-sign) * n.x);
    t = Vec3<T>(b, T(sign) + n.y * n.y * a, -n.y);
}

template <typename T> struct Frame {
    Vec3<T> s, t, n;
    Frame() : s(T(1), T(0), T(0)), t(T(0), T(1), T(0)), n(T(0), T(0), T(1)) {}
    explicit Frame(const Vec3<T>& normal) : n(normal) { coordinate_system(n, s, t); }
    Frame(const Vec3<T>& s, const Vec3<T>& t, const Vec3<T>& n) : s(s), t(t), n(n) {}
    Vec3<T> to_local(const Vec3<T>& v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
    Vec3<T> to_world(const Vec3<T>& v) const { return s * v.x + t * v.y + n * v.z; }

    // Trigonometry of a local direction (pbrt/Mitsuba conventions).
    static T cos_theta(const Vec3<T>& v) { return v.z; }
    static T cos_theta2(const Vec3<T>& v) { return v.z * v.z; }
    static T sin_theta2(const Vec3<T>& v) { return T(1) - v.z * v.z; }
    static T tan_theta2(const Vec3<T>& v) {
        return (T(1) - v.z * v.z) / (v.z * v.z);
    }
};

using Frame3f = Frame<float>;

} // namespace penumbra
