// Unidirectional path tracing with next-event estimation and MIS, the one surface path walk: written once for
// rendering (T = float on the reference geometry), for the interior term of the material-form differential path
// integral (T = Var on the moving geometry, paper 001 §5.1), and for warped-area sampling (paper 004) and
// warped-area reparameterization (paper 000), each of which supplies its vertex rule (VertexRule below).
//
// Paths are always sampled with float arithmetic in the reference configuration (MIS weights and Russian
// roulette are detached). The measurement contribution is written in area measure, f(x̄) ∏ J / p(x̄):
// each segment contributes  f_s(x_{i-1} ← x_i → x_{i+1}) G'(x_i, x_{i+1}) J(x_{i+1}) / (p_σ G'_0),
// with G' = |n_{i+1} · ω| / |x_{i+1} - x_i|² and p_σ the solid-angle density the sampler used. In the reference
// configuration G'/G'_0 = J = 1 and this is the usual estimator; the rule supplies x_i(θ) and J.
#pragma once
#include "render/emitter_hit.h"
#include "render/integrator.h"
#include "render/mis.h"
#include "scene/shape_interaction.h"

#include <type_traits>

namespace penumbra {

// v / detach(v): 1 with a derivative (the relative change of a quantity away from the reference configuration).
template <typename T> inline T relative_change(const T& v) {
    if constexpr (std::is_same_v<T, float>) return 1.f;
    else return v / T(detach(v));
}

// Russian roulette, detached (Mitsuba 3: survival probability min(max(throughput / scale)·eta², 0.95)): false
// when the path ends, else the throughput is divided by the survival probability. `scale` is the estimate's
// own factor that the rule should not see (volpath_tracer.h's mean free-flight ratio; 1 otherwise).
inline float roulette_survival(const Color3f& throughput, float eta, float scale = 1.f) {
    return std::min(max_component(throughput / scale) * eta * eta, 0.95f);
}
template <typename T>
bool survives_roulette(Color3<T>& throughput, float eta, Sampler& sampler, float scale = 1.f) {
    const float q =
        roulette_survival(Color3f(detach(throughput.x), detach(throughput.y), detach(throughput.z)), eta, scale);
    if (sampler.next_1d() >= q) return false;
    throughput /= T(q);
    return true;
}

// The reference geometry: vertices are the float hits themselves.
struct ReferenceGeometry {
    const SurfaceInteraction3f& vertex(const SurfaceInteraction3f& hit) const { return hit; }
    float jacobian(const SurfaceInteraction3f&) const { return 1.f; }
    Vec3f position(const Shape& shape, uint32_t v) const { return shape.mesh.positions[v]; }
    Vec3f medium_vertex(const Vec3f& p, const Medium*, float& jacobian) const { return jacobian = 1.f, p; }
    Vec3f light_position(const Emitter&, const Vec3f& p) const { return p; }
    Vec3f light_direction(const Emitter&, const Vec3f& d) const { return d; }
    Vec3f to_reference_light(const Emitter&, const Vec3f& x) const { return x; }
    Vec3f direction_to_reference_light(const Emitter&, const Vec3f& d) const { return d; }
};

// The emitter's side of a next-event connection from x in material form (T = Var): the unit direction wo
// from x toward the light and the factor L_e G' J / (p_σ G'_0) of an area light at material point y, the
// incident term I / p of a point, spot or directional light (Eq. 24, evaluated on the reference light at x
// moved by the light's inverse motion; toward a point light the direction moves with x and with the light, a
// directional light's turns with it), or the environment's radiance along the fixed direction over p.
// `light` receives the light's point (area and point lights) for the visibility of the connection.
template <typename T> struct EmitterConnection {
    Vec3<T> wo;
    Color3<T> value;
    Vec3<T> light;
    bool finite = false; // the connection ends at `light`
};

template <typename T, typename Geometry>
EmitterConnection<T> emitter_connection(const DirectionSample3f& ds, const Vec3<T>& x, const Geometry& geometry) {
    using std::abs;
    using std::sqrt;
    const Emitter* emitter = ds.emitter;
    EmitterConnection<T> c;
    if (const Shape* shape = emitter->shape()) {
        const SurfaceInteraction3f light_hit =
            surface_interaction<float>(*shape, ds.prim, ds.bary, MeshVertices{shape->mesh});
        SurfaceInteraction<T> y = geometry.vertex(light_hit);
        const Vec3<T> to_light = y.p - x;
        const T dist2 = squared_norm(to_light);
        c.wo = to_light / sqrt(dist2);
        y.wi = y.to_local(-c.wo);
        const T g = abs(dot(y.n, c.wo)) / dist2;
        c.value = emitter->eval(y) * (relative_change(g * geometry.jacobian(light_hit)) / T(ds.pdf));
        c.light = y.p;
        c.finite = true;
    } else if (emitter->is_delta()) {
        if (emitter->is_infinite()) {
            c.wo = geometry.light_direction(*emitter, ds.d);
        } else {
            c.light = geometry.light_position(*emitter, ds.p);
            c.wo = normalize(c.light - x);
            c.finite = true;
        }
        c.value = emitter->eval_delta(geometry.to_reference_light(*emitter, x)) / T(ds.pdf);
    } else {
        c.wo = Vec3<T>(ds.d);
        c.value = emitter->eval_environment(geometry.direction_to_reference_light(*emitter, ds.d)) / T(ds.pdf);
    }
    return c;
}

// Next-event contribution f_s L_e / p at x in material form (T = Var), for the emitter sample ds.
template <typename T, typename Geometry>
Color3<T> next_event_contribution(const BSDFContext& ctx, const BSDF* bsdf, const SurfaceInteraction<T>& si,
                                  const DirectionSample3f& ds, const Geometry& geometry) {
    const EmitterConnection<T> c = emitter_connection(ds, si.p, geometry);
    return bsdf->eval(ctx, si, si.to_local(c.wo)) * c.value;
}

// A step through the delta lobe sampled in `bs` at x (T = Var: `si` on the tape with its wi set): the lobe
// fixes the direction given the incident one (its half vector stays in the shading frame, scene/bsdf.h
// delta_direction), so the direction turns with the geometry, and its smooth factor g (Fresnel) follows the
// angles: multiplies the throughput by g / p and returns the world direction.
template <typename T>
Vec3<T> delta_step(const BSDF& bsdf, const SurfaceInteraction3f& hit, const SurfaceInteraction<T>& si,
                   const BSDFSample& bs, Color3<T>& throughput) {
    const Vec3<T> wo = delta_direction(si.wi, hit.wi, bs);
    throughput *= bsdf.delta_weight(BSDFContext{TransportMode::Radiance}, si, wo) / T(bs.pdf);
    return si.to_world(wo);
}

// A vertex rule of trace_path: how each vertex of a path sampled in the reference configuration is placed in T,
// and what each contribution carries there. Rules are per path (they may keep the path's state):
//   SurfaceInteraction<T> arrive(hit, prev)   the vertex `hit`, reached by BSDF sampling from `prev`, in T with
//                                             its `wi` set (toward `prev`);
//   Color3<T> emitted(e, Le, hit, si, d)       the radiance L_e of emitter e (float value Le) seen at `hit` (si in
//                                             T), or the environment along d when `hit` is invalid;
//   Color3<T> next_event(bsdf, hit, si, ds, em_weight, rays)   f_s L_e / p of the emitter sample ds
//                                             (em_weight = L_e / p in the reference configuration);
//   void scatter(bsdf, hit, si, bs, weight, d, next, delta, throughput, rays)   multiplies the throughput by the
//                                             step's factor f_s G J / (G_0 p_σ) to `next` (invalid: escaped along
//                                             d; weight = f/p in float, delta: a delta lobe was sampled).
// and optionally
//   optional<Color3<T>> attached_boundary(bsdf, hit, si, depth, rays)   a boundary term that no edge carries
//                                             of the light scattered at the vertex, as a value-0 quantity whose
//                                             derivative is the term's, or none (diff/psdr/shading_horizon.h).
// The primal (T = float on the reference geometry) and paper 001's material-form interior term (T = Var on the
// moving geometry) are GeometryRule; warped-area sampling (diff/was/warped_area.cpp) and warped-area
// reparameterization (diff/war/war.cpp) warp the vertices with their fields.
template <typename Rule>
concept VertexRule = requires { &Rule::scatter; };

// Radiance leaving the first vertex of a path toward the sensor, estimated along one sampled path. `first` is
// the intersection of `primary` (traced by the caller) and `first_si` the same vertex in T with its `wi`
// (toward the sensor) set; for T = float it is `first` itself.
template <typename T, VertexRule Rule>
Color3<T> trace_path(const Scene& scene, Sampler& sampler, const Ray& primary, const SurfaceInteraction3f& first,
                     const SurfaceInteraction<T>& first_si, Rule& rule, const PathSettings& settings,
                     RayCounter& rays) {
    const BSDFContext ctx{TransportMode::Radiance};
    Color3<T> L(T(0)), throughput(T(1));
    if (settings.max_depth == 0) return L;
    const unsigned max_depth = unsigned(settings.max_depth); // -1 wraps to "infinite"
    float eta = 1.f;

    Ray ray = primary;
    SurfaceInteraction3f hit = first, prev_hit;
    SurfaceInteraction<T> si = first_si;
    float prev_bsdf_pdf = 1.f;
    bool prev_bsdf_delta = true;

    for (unsigned depth = 0;; ++depth) {
        // Emission reached by BSDF sampling (or directly visible), MIS-weighted against emitter sampling.
        if (depth > 0 && hit.is_valid()) si = rule.arrive(hit, si);
        if (!(depth == 0 && settings.hide_emitters)) {
            for_each_emitter_hit(scene, prev_hit, ray.d, hit, [&](const Emitter* e, const Color3f& Le, float emitter_pdf) {
                const float w = prev_bsdf_delta ? 1.f : mis_power(prev_bsdf_pdf, emitter_pdf);
                L += throughput * rule.emitted(*e, Le, hit, si, ray.d) * T(w);
            });
        }
        if (!hit.is_valid() || depth + 1 >= max_depth) break;
        const BSDF* bsdf = hit.bsdf();
        if (!bsdf) break;

        // Next-event estimation.
        if (bsdf->has(BSDFSmooth) && !scene.emitters.empty()) {
            const auto [ds, em_weight] = scene.sample_emitter_direction(hit, sampler.next_2d(), true);
            ++rays.rays;
            if (!is_black(em_weight)) {
                const Color3<T> contribution = rule.next_event(*bsdf, hit, si, ds, em_weight, rays);
                const float w = ds.delta ? 1.f : mis_power(ds.pdf, bsdf->pdf(ctx, hit, hit.to_local(ds.d)));
                L += throughput * contribution * T(w);
            }
            if constexpr (requires { rule.attached_boundary(*bsdf, hit, si, depth, rays); })
                if (const auto term = rule.attached_boundary(*bsdf, hit, si, depth, rays))
                    L += throughput * *term;
        } else {
            sampler.next_2d(); // keep the sample stream aligned across materials
        }

        // BSDF sampling in the reference configuration.
        const float u1 = sampler.next_1d();
        const auto [bs, weight] = bsdf->sample(ctx, hit, u1, sampler.next_2d());
        if (is_black(weight)) break;
        const Vec3f d = hit.to_world(bs.wo);
        ray = hit.spawn_ray(d);
        ++rays.rays;
        const SurfaceInteraction3f next = scene.intersect(ray);
        const bool delta = (bs.sampled_type & BSDFDelta) != 0;
        rule.scatter(*bsdf, hit, si, bs, weight, d, next, delta, throughput, rays);
        eta *= bs.eta;
        prev_hit = hit;
        prev_bsdf_pdf = bs.pdf;
        prev_bsdf_delta = delta;
        hit = next;

        if (depth + 1 >= unsigned(settings.rr_depth) && !survives_roulette(throughput, eta, sampler)) break;
    }
    return L;
}

// The vertex rule of a Geometry (paper 001 §5.1): vertices are the material points of the sampled hits placed by
// the geometry x(p, θ), with the area Jacobian J; T = float on ReferenceGeometry is the primal estimator. On the
// tape a vertex reached by a BSDF sample follows the geometry's flow from its predecessor (MaterialForm's
// contact flow: the material point away from contacts).
template <typename T, typename Geometry> struct GeometryRule {
    static constexpr bool reference = std::is_same_v<T, float>;
    const Geometry& geometry;
    SurfaceInteraction<T> next{}; // the vertex scatter() placed, which arrive() returns
    bool placed = false;
    Vec3<T> steered{}; // the direction scatter() left along (a delta lobe's turns with the geometry)

    SurfaceInteraction<T> arrive(const SurfaceInteraction3f& hit, const SurfaceInteraction<T>& prev) {
        SurfaceInteraction<T> si = placed ? next : geometry.vertex(hit);
        placed = false;
        if constexpr (reference) si.wi = hit.wi;
        else si.wi = si.to_local(normalize(prev.p - si.p));
        return si;
    }

    Color3<T> emitted(const Emitter& e, const Color3f& Le, const SurfaceInteraction3f& hit,
                      const SurfaceInteraction<T>& si, const Vec3f& d) const {
        if constexpr (reference) return Le;
        else
            return hit.is_valid() ? e.eval(si)
                                  : e.eval_environment(geometry.direction_to_reference_light(e, d) +
                                                       (steered - Vec3<T>(d)));
    }

    Color3<T> next_event(const BSDF& bsdf, const SurfaceInteraction3f&, const SurfaceInteraction<T>& si,
                         const DirectionSample3f& ds, const Color3f& em_weight, RayCounter&) const {
        const BSDFContext ctx{TransportMode::Radiance};
        // In the reference configuration the emitter's sampling weight L_e/p is this same quantity.
        if constexpr (reference) return bsdf.eval(ctx, si, si.to_local(ds.d)) * em_weight;
        else return next_event_contribution(ctx, &bsdf, si, ds, geometry);
    }

    void scatter(const BSDF& bsdf, const SurfaceInteraction3f& hit, const SurfaceInteraction<T>& si,
                 const BSDFSample& bs, const Color3f& weight, const Vec3f& d,
                 const SurfaceInteraction3f& next_hit, bool delta, Color3<T>& throughput, RayCounter&) {
        if constexpr (!reference) steered = Vec3<T>(d);
        using std::abs;
        using std::sqrt;
        const BSDFContext ctx{TransportMode::Radiance};
        if constexpr (reference) {
            throughput *= Color3<T>(weight); // weight = f/p
        } else if (delta) {
            // No area integral after a delta lobe (G' and J left out): the next vertex is where its direction
            // from x(θ) meets the moving surface.
            steered = delta_step(bsdf, hit, si, bs, throughput);
            if (next_hit.is_valid()) {
                next = geometry.ray_vertex(next_hit, si.p, steered);
                placed = true;
            }
        } else if (next_hit.is_valid()) {
            T jacobian;
            next = geometry.flowed_vertex(next_hit, si.p, jacobian);
            placed = true;
            const Vec3<T> to_next = next.p - si.p;
            const T dist2 = squared_norm(to_next);
            const Vec3<T> wo = to_next / sqrt(dist2);
            const T g = abs(dot(next.n, wo)) / dist2;
            throughput *= bsdf.eval(ctx, si, si.to_local(wo)) * (relative_change(g * jacobian) / T(bs.pdf));
        } else {
            throughput *= bsdf.eval(ctx, si, si.to_local(Vec3<T>(d))) / T(bs.pdf);
        }
    }
};

// trace_path with the vertex rule of a Geometry (ReferenceGeometry for the primal, MaterialForm on the tape).
template <typename T, typename Geometry>
    requires(!VertexRule<Geometry>)
Color3<T> trace_path(const Scene& scene, Sampler& sampler, const Ray& primary, const SurfaceInteraction3f& first,
                     const SurfaceInteraction<T>& first_si, const Geometry& geometry, const PathSettings& settings,
                     RayCounter& rays) {
    GeometryRule<T, Geometry> rule{geometry};
    return trace_path<T>(scene, sampler, primary, first, first_si, rule, settings, rays);
}

} // namespace penumbra
