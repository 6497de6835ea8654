// The measurement contribution f(x̄) of a bidirectional path in material form (paper 001 §4.1, §5.1, §7),
// written once on the scalar type T over a Geometry (MaterialForm on the tape; render/path_tracer.h's
// ReferenceGeometry in float). The path x̄ = z_0 z_1 ... z_{t-1} y_{s-1} ... y_0 is ordered from the camera
// z_0 to the light y_0 (Veach 1997, Eq. 8.7):
//   f(x̄) = W · Π_i f_s(x_i) · Π_segments G(x_i, x_{i+1}) Tr(x_i, x_{i+1}) · Π_{medium x_i} σ_s(x_i) · L_e
//          · Π_i J(x_i),
// with the scattering function evaluated toward the light side (its |cos| there included, as BSDF::eval
// does), so that each segment keeps the |cos| of its light-side end over ℓ² (1/ℓ² when that end is a medium
// vertex: a volume measure), the Jacobians J = dA(x)/dA(p) or dV(x)/dV(p) of the material form (Eq. 17,
// Eq. 46), and the transmittance of each segment re-evaluated from the chain it was sampled with
// (render/flight_record.h: free flights σ_s Tr along subpath segments, ratio-tracking transmittance along
// connections; crossings of null surfaces slide along the moving segment). The camera factor of z_1 is the
// caller's (image-space or material-form first vertex, diff/psdr/interior_media.h). Constant factors (sampling
// densities, the scattering functions of delta lobes) are left out: the estimator uses f(x̄; θ) / f(x̄; θ0).
// After a delta lobe the next vertex follows its direction: as in render/volpath_tracer.h, that segment's
// G' and the vertex's J are left out.
#pragma once
#include "core/var.h"
#include "render/bdpt_record.h"
#include "render/path_tracer.h"

namespace penumbra {

// A path vertex on the geometry: a surface vertex (its moving interaction), a medium vertex, a light's point
// or an escaped direction (at `p` = previous vertex + direction).
template <typename T> struct MeasuredVertex {
    const PathVertex* ref = nullptr;
    Vec3<T> p;
    SurfaceInteraction<T> si;
    T jacobian = T(1.f);
    bool surface = false, infinite = false;
};

// An escaped camera ray's vertex (the environment): a point one unit along the world direction d from the
// vertex before it, which only the direction it gives matters for.
template <typename T> MeasuredVertex<T> escaped_vertex(const PathVertex& v, const Vec3<T>& before, const Vec3f& d) {
    MeasuredVertex<T> x;
    x.ref = &v;
    x.infinite = true;
    x.p = before + Vec3<T>(d);
    return x;
}

// A scattering vertex or an area light's point of the reference path on the geometry.
template <typename T, typename Geometry>
MeasuredVertex<T> measured_vertex(const PathVertex& v, const Geometry& geometry) {
    MeasuredVertex<T> m;
    m.ref = &v;
    if (v.type == VertexType::Medium) {
        m.p = geometry.medium_vertex(v.p, v.medium, m.jacobian);
    } else if (v.type == VertexType::Light && !v.emitter->shape()) {
        m.p = geometry.light_position(*v.emitter, v.p); // a point-like light
    } else {
        m.si = geometry.vertex(v.si);
        m.p = m.si.p;
        m.jacobian = geometry.jacobian(v.si);
        m.surface = true;
    }
    return m;
}

// The scattering function at v from its camera-side neighbor toward the light side (radiance transport);
// at a delta lobe its smooth factor g (scene/bsdf.h delta_weight).
template <typename T>
Color3<T> measured_scattering(const MeasuredVertex<T>& v, const Vec3<T>& camera_side, const Vec3<T>& wo) {
    const Vec3<T> wi = normalize(camera_side - v.p);
    if (!v.surface) return Color3<T>(v.ref->medium->phase->template eval<T>(wi, wo));
    SurfaceInteraction<T> si = v.si;
    si.wi = si.to_local(wi);
    const BSDFContext ctx{TransportMode::Radiance};
    if (v.ref->delta) return v.ref->si.bsdf()->delta_weight(ctx, si, si.to_local(wo));
    return v.ref->si.bsdf()->eval(ctx, si, si.to_local(wo));
}

// The vertex b after a delta lobe at the surface vertex a (reached from `from`): where the lobe's direction
// from a(θ) (render/path_tracer.h delta_step) meets b's moving surface, at b's free-flight distance in a
// medium, or that direction itself for an escaped b; no area integral at b (J = 1).
template <typename Geometry>
MeasuredVertex<Var> steered_vertex(const PathVertex& b, const MeasuredVertex<Var>& a, const Vec3<Var>& from,
                                   const Geometry& geometry) {
    const SurfaceInteraction3f& hit = a.ref->si;
    const Vec3f wo0 = b.infinite ? b.d_env : normalize(b.p - a.ref->p);
    BSDFSample bs;
    bs.wo = hit.to_local(wo0);
    bs.eta = a.ref->eta;
    bs.sampled_type = hit.wi.z * bs.wo.z > 0.f ? BSDFDeltaReflection
                      : bs.eta == 1.f          ? BSDFNull
                                               : BSDFDeltaTransmission;
    SurfaceInteraction<Var> si = a.si;
    si.wi = si.to_local(normalize(from - a.p));
    const Vec3<Var> d = si.to_world(delta_direction(si.wi, hit.wi, bs));
    MeasuredVertex<Var> m;
    m.ref = &b;
    m.infinite = b.infinite;
    if (b.infinite || b.type == VertexType::Medium) {
        m.p = a.p + (b.infinite ? d : d * Var(norm(b.p - a.ref->p)));
        return m;
    }
    m.si = geometry.ray_vertex(b.si, a.p, d);
    m.p = m.si.p;
    m.surface = true;
    return m;
}

// G' of the light-side end b of a segment a → b: |cos θ_b| / ℓ² (surface) or 1 / ℓ² (medium); 1 toward a
// direction.
template <typename T> T measured_geometry(const MeasuredVertex<T>& a, const MeasuredVertex<T>& b) {
    using std::abs;
    using std::sqrt;
    if (b.infinite) return T(1.f);
    const Vec3<T> w = b.p - a.p;
    const T dist2 = squared_norm(w);
    return b.surface ? abs(dot(b.si.n, w)) / (dist2 * sqrt(dist2)) : T(1.f) / dist2;
}

// The free-flight weights σ_s Tr of a subpath segment a → b sampled along `chain` (b scattering in a medium).
template <typename T, typename Geometry>
Color3<T> measured_flight(const LegChain& chain, const MeasuredVertex<T>& a, const MeasuredVertex<T>& b,
                          const Geometry& geometry) {
    return chain_weight(chain, a.p, b.p, true, b.ref->type == VertexType::Medium, b.infinite, geometry);
}

// Emission of the light subpath's origin y0 toward y1 with the segment's G' and J(y0) (area light), or the
// incident intensity I / ℓ² of a point-like light at y1 (Eq. 24: the light's inverse motion applied to y1).
template <typename T, typename Geometry>
Color3<T> measured_emission(const MeasuredVertex<T>& y0, const MeasuredVertex<T>& y1,
                            const Geometry& geometry) {
    const Emitter& e = *y0.ref->emitter;
    if (!y0.surface) return e.eval_delta(geometry.to_reference_light(e, y1.p));
    SurfaceInteraction<T> si = y0.si;
    si.wi = si.to_local(normalize(y1.p - y0.p));
    return e.eval(si) * (measured_geometry(y1, y0) * y0.jacobian);
}

// The camera subpath's factors up to z_k (its J included), without z_k's scattering: prefix[k] for
// k = 1 .. n-1 (z_0 at `camera`; z_1's camera factor, with its J, left out).
template <typename T, typename Geometry>
void camera_prefix(const std::vector<MeasuredVertex<T>>& z, const Vec3<T>& camera, const BDPTRecord& record,
                   const Geometry& geometry, std::vector<Color3<T>>& prefix) {
    prefix.assign(z.size(), Color3<T>(T(1.f)));
    MeasuredVertex<T> origin;
    origin.p = camera;
    for (size_t k = 1; k < z.size(); ++k) {
        const MeasuredVertex<T>& before = k == 1 ? origin : z[k - 1];
        Color3<T> c = measured_flight(record.camera[k], before, z[k], geometry);
        if (k >= 2) {
            const Vec3<T> camera_side = k == 2 ? camera : z[k - 2].p;
            c *= prefix[k - 1] * measured_scattering(z[k - 1], camera_side, normalize(z[k].p - z[k - 1].p));
            if (!z[k - 1].ref->delta) c *= measured_geometry(z[k - 1], z[k]) * z[k].jacobian;
        }
        prefix[k] = c;
    }
}

// The light subpath's factors from y_0 up to y_k (its J included), without y_k's scattering: prefix[k] for
// k = 1 .. n-1.
template <typename T, typename Geometry>
void light_prefix(const std::vector<MeasuredVertex<T>>& y, const BDPTRecord& record, const Geometry& geometry,
                  std::vector<Color3<T>>& prefix) {
    prefix.assign(y.size(), Color3<T>(T(1.f)));
    for (size_t k = 1; k < y.size(); ++k) {
        Color3<T> c = measured_flight(record.light[k], y[k - 1], y[k], geometry);
        if (k == 1)
            c *= measured_emission(y[0], y[1], geometry) * y[1].jacobian;
        else
            c *= prefix[k - 1] * measured_scattering(y[k - 1], y[k].p, normalize(y[k - 2].p - y[k - 1].p));
        if (k >= 2 && !y[k - 1].ref->delta) c *= measured_geometry(y[k], y[k - 1]) * y[k].jacobian;
        prefix[k] = c;
    }
}

// f(x̄) of strategy (s, t >= 2) without z_1's camera factor, from the subpaths' prefixes.
template <typename T, typename Geometry>
Color3<T> path_measurement(const StrategyRecord& st, const std::vector<MeasuredVertex<T>>& z,
                           const std::vector<MeasuredVertex<T>>& y, const std::vector<Color3<T>>& camera,
                           const std::vector<Color3<T>>& light, const Vec3<T>& camera_position,
                           const Scene& scene, const Geometry& geometry) {
    const MeasuredVertex<T>& zt = z[size_t(st.t - 1)];
    const Vec3<T> camera_side = st.t == 2 ? camera_position : z[size_t(st.t - 2)].p;
    const Color3<T>& head = camera[size_t(st.t - 1)];
    if (st.s == 0) {
        if (zt.infinite) {
            Color3<T> L(T(0.f));
            // Along z_{t−1} − z_{t−2}: d_env, turned by a delta lobe before it.
            const Vec3<T> turn = zt.p - camera_side - Vec3<T>(zt.ref->d_env);
            for (const auto& e : scene.emitters)
                if (e->is_infinite() && !e->is_delta())
                    L += e->eval_environment(geometry.direction_to_reference_light(*e, zt.ref->d_env) + turn);
            return head * L;
        }
        SurfaceInteraction<T> si = zt.si;
        si.wi = si.to_local(normalize(camera_side - zt.p));
        return head * zt.ref->emitter->eval(si);
    }
    if (st.s == 1) {
        const EmitterConnection<T> c = emitter_connection(st.light_sample, zt.p, geometry);
        const Vec3<T> end = c.finite ? c.light : zt.p + c.wo;
        return head * measured_scattering(zt, camera_side, c.wo) * c.value *
               chain_weight(st.connection, zt.p, end, false, false, !c.finite, geometry);
    }
    const MeasuredVertex<T>& ys = y[size_t(st.s - 1)];
    const Vec3<T> w = normalize(ys.p - zt.p);
    return head * measured_scattering(zt, camera_side, w) *
           chain_weight(st.connection, zt.p, ys.p, false, false, false, geometry) *
           measured_geometry(zt, ys) *
           measured_scattering(ys, zt.p, normalize(y[size_t(st.s - 2)].p - ys.p)) * light[size_t(st.s - 1)];
}

// f / detach(f), one where the reference value vanishes (the strategy's contribution does too).
inline Var relative(const Var& f) { return f.v != 0.f && std::isfinite(f.v) ? f / Var(f.v) : Var(1.f); }

// Σ_{s,t} C_{s,t} f(x̄; θ) / f(x̄; θ0) over the recorded strategies (render/bdpt_sample.h) that contribute,
// f(x̄; θ) = measurement(st) the strategy's path on the geometry: the estimator at θ0 is the renderer's, its
// sampling densities and MIS weights detached (paper 001 §7, paper 000 Eq. 54).
template <typename Measurement>
Color3<Var> reweighted_strategies(const BDPTRecord& record, Measurement&& measurement) {
    Color3<Var> L(Var(0.f));
    for (int k = 0; k < record.count; ++k) {
        const StrategyRecord& st = record.strategies[size_t(k)];
        if (is_black(st.value)) continue;
        const Color3<Var> f = measurement(st);
        L += Color3<Var>(Var(st.value.x) * relative(f.x), Var(st.value.y) * relative(f.y),
                         Var(st.value.z) * relative(f.z));
    }
    return L;
}

} // namespace penumbra
