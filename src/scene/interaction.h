// Points on paths: surface interactions, and the position/direction samples used by emitters and sensors.
#pragma once
#include "core/frame.h"
#include "core/math.h"

#include <cstdint>

namespace penumbra {

class Shape;
class BSDF;
class Emitter;

struct Ray {
    Vec3f o, d;
    float tmax = Infinity;
    Ray() = default;
    Ray(const Vec3f& o, const Vec3f& d, float tmax = Infinity) : o(o), d(d), tmax(tmax) {}
    Vec3f operator()(float t) const { return o + d * t; }
};

// A reference point: position and geometric normal (zero normal for points in media / on point lights).
template <typename T> struct Interaction {
    T t = T(Infinity); // distance along the ray that found it
    Vec3<T> p;
    Vec3<T> n;

    // Ray leaving this point in world direction d, offset to avoid self-intersection.
    Ray spawn_ray(const Vec3f& d) const;
    // Shadow ray from this point to `target` (stops just short of it).
    Ray spawn_ray_to(const Vec3f& target) const;
};

template <typename T> struct SurfaceInteraction : Interaction<T> {
    Frame<T> sh_frame;    // shading frame in world space (n = shading normal)
    Vec2<T> uv;           // texture coordinates
    Vec3<T> wi;           // direction toward the previous path vertex, in the local shading frame
    Vec2f bary;           // barycentrics (b1, b2) of the hit in triangle prim_index
    const Shape* shape = nullptr;
    uint32_t prim_index = 0;

    bool is_valid() const { return shape != nullptr; }
    Vec3<T> to_local(const Vec3<T>& v) const { return sh_frame.to_local(v); }
    Vec3<T> to_world(const Vec3<T>& v) const { return sh_frame.to_world(v); }
    // Defined in shape.h (needs the Shape definition).
    const BSDF* bsdf() const;
    const Emitter* emitter() const;
};

// A sampled point on an emitter or sensor. `pdf` is an area density, or a discrete probability for delta positions.
template <typename T> struct PositionSample {
    Vec3<T> p;
    Vec3<T> n;
    Vec2<T> uv;
    T pdf = T(0);
    bool delta = false;
    // The material point sampled on a mesh (triangle and barycentrics), for re-evaluation in material form.
    uint32_t prim = 0;
    Vec2f bary;
};

// A sampled point seen from a reference point. `d` is the unit direction from the reference to `p`, `dist`
// the distance, `pdf` a solid-angle density (or discrete probability for delta emitters/sensors).
// For sensors `uv` holds the continuous film position in pixels.
template <typename T> struct DirectionSample : PositionSample<T> {
    Vec3<T> d;
    T dist = T(0);
    const Emitter* emitter = nullptr;
};

using SurfaceInteraction3f = SurfaceInteraction<float>;
using Interaction3f = Interaction<float>;
using DirectionSample3f = DirectionSample<float>;
using PositionSample3f = PositionSample<float>;

// --- ray spawning -----------------------------------------------------------------------------------------
inline float ray_offset_scale(const Vec3f& p) {
    return RayEpsilon * (1.f + max_component(abs(p)));
}
template <typename T> Ray Interaction<T>::spawn_ray(const Vec3f& d) const {
    const Vec3f pf(detach(p.x), detach(p.y), detach(p.z));
    const Vec3f nf(detach(n.x), detach(n.y), detach(n.z));
    const float side = dot(nf, d) >= 0.f ? 1.f : -1.f;
    return Ray(pf + nf * (side * ray_offset_scale(pf)), d);
}
template <typename T> Ray Interaction<T>::spawn_ray_to(const Vec3f& target) const {
    const Vec3f pf(detach(p.x), detach(p.y), detach(p.z));
    const Vec3f nf(detach(n.x), detach(n.y), detach(n.z));
    const Vec3f to = target - pf;
    const float side = dot(nf, to) >= 0.f ? 1.f : -1.f;
    const Vec3f o = pf + nf * (side * ray_offset_scale(pf));
    const Vec3f d = target - o;
    const float dist = norm(d);
    return Ray(o, d / dist, dist * (1.f - 1e-3f));
}

} // namespace penumbra
