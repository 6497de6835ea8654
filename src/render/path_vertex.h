// Path-space vocabulary shared by the forward integrators and the estimators built on them (BDPT, boundary
// sampling, photon mapping): vertices with their densities, and the measure conversions between them.
#pragma once
#include "scene/interaction.h"

namespace penumbra {

// Geometry term G(x, y) = |cos θ_x| |cos θ_y| / |x - y|^2 (either normal may be zero: point vertices).
template <typename T> T geometry_term(const Vec3<T>& x, const Vec3<T>& nx, const Vec3<T>& y, const Vec3<T>& ny) {
    using std::abs;
    using std::sqrt;
    const Vec3<T> d = y - x;
    const T dist2 = squared_norm(d);
    const Vec3<T> w = d / sqrt(dist2);
    const T cx = squared_norm(nx) > T(0) ? abs(dot(nx, w)) : T(1);
    const T cy = squared_norm(ny) > T(0) ? abs(dot(ny, w)) : T(1);
    return cx * cy / dist2;
}

// Converts a solid-angle density at `from` toward the point `to` (normal `n_to`) to an area density at `to`.
inline float pdf_solid_angle_to_area(float pdf_sa, const Vec3f& from, const Vec3f& to, const Vec3f& n_to) {
    const Vec3f d = to - from;
    const float dist2 = squared_norm(d);
    const float cos_to = squared_norm(n_to) > 0.f ? std::abs(dot(n_to, d)) / std::sqrt(dist2) : 1.f;
    return pdf_sa * cos_to / dist2;
}

// A vertex of a sampled path: where it is, how it was sampled, and how much it carries.
struct PathVertex {
    enum class Type { Camera, Light, Surface };
    Type type = Type::Surface;
    SurfaceInteraction3f si;   // position, normals, local frame, shape
    Color3f throughput{1.f};   // product of weights up to and including this vertex
    float pdf_fwd = 0.f;       // area density of sampling this vertex from its predecessor
    bool delta = false;        // sampled by a delta lobe (not connectible)
};

} // namespace penumbra
