#include "diff/war/war.h"

#include "diff/film_sample.h"
#include "diff/material_form.h"
#include "diff/pixel_driver.h"
#include "diff/specular_chains.h"
#include "render/light_medium.h"
#include "render/path_tracer.h"

#include <cstdio>

namespace penumbra {

namespace {

// What the estimator of one scene shares across samples.
struct WarContext {
    const Scene& scene;
    const Parameters& params;
    MaterialForm form;
    BoundaryTest boundary;
    WarScene field;
    PathSettings settings;
    bool environment = false; // an infinite emitter that is not delta (MaterialForm::environment's sum)

    WarContext(const Scene& s, const Parameters& p, const WarOptions& o)
        : scene(s), params(p), form(s, p, FirstVertex::Material),
          boundary(s), field{s, p, form, boundary, o.field}, settings(o.path) {
        for (const auto& e : s.emitters)
            environment = environment || (e->is_infinite() && !e->is_delta());
    }
};

// The vertex rule of the unidirectional estimator (render/path_tracer.h; Algorithm 2 lines 6–17): every vertex
// warped by the field conditioned on its detector-side neighbour as it is sampled, p(θ) = p + (θ − θ0) v(p)
// with the factor 1 + (θ − θ0) ∇·v in its area Jacobian.
struct WarRule {
    const WarContext& c;
    AuxiliaryRng& rng;
    Vec3<Var> material;           // the current vertex's material point, for its field's conditioning
    Vec3<Var> escaped;            // the direction an escaped ray left along, warped on the sphere
    SurfaceInteraction<Var> next; // the vertex the last step placed

    SurfaceInteraction<Var> arrive(const SurfaceInteraction3f&, const SurfaceInteraction<Var>&) const {
        return next;
    }

    Color3<Var> emitted(const Emitter& e, const Color3f&, const SurfaceInteraction3f& hit,
                        const SurfaceInteraction<Var>& si, const Vec3f& d) const {
        return hit.is_valid() ? e.eval(si) : c.form.environment(c.scene, d, escaped);
    }

    // Next-event estimation at the detector vertex p^D_n (Algorithm 2 lines 7–10): the light vertex p^S_n
    // warped conditioned on p^D_n, f_s L_e G J (1 + ∇·v) / (G_0 p_σ); the environment's direction warped on
    // the sphere; delta lights connected in material form without a warp.
    Color3<Var> next_event(const BSDF& bsdf, const SurfaceInteraction3f& hit, const SurfaceInteraction<Var>& si,
                           const DirectionSample3f& ds, const Color3f&, RayCounter& rays) {
        const BSDFContext ctx{TransportMode::Radiance};
        if (ds.emitter->is_delta()) return next_event_contribution(ctx, &bsdf, si, ds, c.form);
        const WarNeighbor here{hit, material};
        if (const Shape* shape = ds.emitter->shape()) {
            const SurfaceInteraction3f light =
                surface_interaction<float>(*shape, ds.prim, ds.bary, MeshVertices{shape->mesh});
            WarVertex y = war_vertex(c.field, light, here, rng, rays.rays);
            const Vec3<Var> to_light = y.si.p - si.p;
            const Var dist2 = squared_norm(to_light);
            const Vec3<Var> wo = to_light / sqrt(dist2);
            y.si.wi = y.si.to_local(-wo);
            const Var g = abs(dot(y.si.n, wo)) / dist2;
            return bsdf.eval(ctx, si, si.to_local(wo)) * ds.emitter->eval(y.si) *
                   (relative_change(g * y.jacobian) / Var(ds.pdf));
        }
        const WarpEstimate e = war_direction(c.field, c.field.options.directions, hit, here.position, ds.d, rng, rays.rays);
        return bsdf.eval(ctx, si, si.to_local(e.direction)) * (e.jacobian / Var(ds.pdf)) *
               ds.emitter->eval_environment(c.form.direction_to_reference_light(*ds.emitter, ds.d) +
                                            (e.direction - Vec3<Var>(ds.d)));
    }

    void scatter(const BSDF& bsdf, const SurfaceInteraction3f& hit, const SurfaceInteraction<Var>& si,
                 const BSDFSample& bs, const Color3f& /*weight*/, const Vec3f& d,
                 const SurfaceInteraction3f& to, bool delta, Color3<Var>& throughput, RayCounter& rays) {
        const BSDFContext ctx{TransportMode::Radiance};
        const WarNeighbor here{hit, material};
        SurfaceInteraction<Var> next_si;
        if (delta) {
            // No area integral after a delta lobe: the next vertex is where its direction meets the surface.
            escaped = delta_step(bsdf, hit, si, bs, throughput);
            if (to.is_valid()) next_si = c.form.ray_vertex(to, si.p, escaped), material = next_si.p;
        } else if (to.is_valid()) {
            // p^D_{n+1} warped conditioned on p^D_n: f_s G J (1 + ∇·v) / (G_0 p_σ).
            const WarVertex x = war_vertex(c.field, to, here, rng, rays.rays);
            const Vec3<Var> to_next = x.si.p - si.p;
            const Var dist2 = squared_norm(to_next);
            const Vec3<Var> wo = to_next / sqrt(dist2);
            const Var g = abs(dot(x.si.n, wo)) / dist2;
            throughput *=
                bsdf.eval(ctx, si, si.to_local(wo)) * (relative_change(g * x.jacobian) / Var(bs.pdf));
            next_si = x.si;
            material = x.material;
        } else {
            const WarpEstimate e = war_direction(c.field, c.field.options.directions, hit, material, d, rng, rays.rays);
            throughput *= bsdf.eval(ctx, si, si.to_local(e.direction)) * (e.jacobian / Var(bs.pdf));
            escaped = e.direction;
        }
        if (to.is_valid()) {
            next_si.wi = next_si.to_local(normalize(si.p - next_si.p));
            next = next_si;
        }
    }
};

// The first vertex of a camera path that escapes: its direction ω warped on the sphere by the field
// conditioned on the camera (the directions that escape form a region bounded by silhouettes, and the region
// moves with them), seen at film position s(ω(θ)) with |ds/dω|(ω(θ)) (1 + ∇·V): the camera factor of the
// material-form first vertex in solid angle, so that the divergence theorem of Eq. 34 closes across the
// silhouettes that separate the environment from the surfaces (whose first vertices war_vertex warps).
struct EscapedFirstVertex {
    Vec3<Var> direction;
    Vec2<Var> s;
    Var jacobian;
};
bool escaped_first_vertex(const WarScene& c, const Ray& ray, AuxiliaryRng& rng, uint64_t& rays,
                          EscapedFirstVertex& out) {
    const WarpEstimate e = war_direction(c, c.options.camera_directions, Interaction3f{Infinity, ray.o, Vec3f(0.f)},
                                         c.form.camera_position(ray.o), ray.d, rng, rays);
    const Vec3<Var> d_cam = c.form.direction_to_reference_camera(e.direction);
    Var film_jacobian;
    if (!c.scene.sensor->film_position(Vec3<Var>(ray.o) + d_cam, -d_cam, out.s, film_jacobian)) return false;
    out.direction = e.direction;
    out.jacobian = film_jacobian * e.jacobian;
    return true;
}

// One camera sample of pixel (px, py): the film position from the defensive filter mixture
// (diff/film_sample.h), the first vertex p^D_1 warped conditioned on the camera, and the camera factor
// P_j(s(x1(θ))) |ds/dA|(θ) J (1 + ∇·v) / (p_s |ds/dA|(θ0)) of the material-form first vertex (paper 001).
Color3<Var> camera_sample(const WarContext& c, Sampler& sampler, AuxiliaryRng& rng, int px, int py,
                          RayCounter& rays) {
    const Sensor& sensor = *c.scene.sensor;
    const Film& film = *sensor.film;
    const FilmSample fs = sample_film(*film.rfilter, sampler, false);
    const Vec2f center(px + 0.5f, py + 0.5f);
    const auto [ray, ray_weight] = sensor.sample_ray(center + fs.offset, sampler.next_2d());
    ++rays.rays;
    const SurfaceInteraction3f first = c.scene.intersect(ray);
    if (!first.is_valid()) {
        // Without an environment the escaped sample carries nothing: no auxiliary rays for its warp.
        if (c.settings.hide_emitters || !c.environment) return Color3<Var>(Var(0.f));
        EscapedFirstVertex x1;
        if (!escaped_first_vertex(c.field, ray, rng, rays.rays, x1)) return Color3<Var>(Var(0.f));
        const Var factor = film.filter_weight(px, py, x1.s) * relative_change(x1.jacobian) / Var(fs.pdf);
        return c.form.environment(c.scene, ray.d, x1.direction) * Color3<Var>(ray_weight) * factor;
    }
    const WarNeighbor camera{Interaction3f{Infinity, ray.o, Vec3f(0.f)}, c.form.camera_position(ray.o)};
    WarVertex x1 = war_vertex(c.field, first, camera, rng, rays.rays);
    const Vec3<Var> p_cam = c.form.to_reference_camera(x1.si.p, ray.o);
    const Vec3<Var> n_cam = c.form.direction_to_reference_camera(x1.si.n);
    Vec2<Var> s;
    Var jacobian;
    if (!sensor.film_position(p_cam, n_cam, s, jacobian)) return Color3<Var>(Var(0.f));
    const Var factor = film.filter_weight(px, py, s) * relative_change(jacobian * x1.jacobian) / Var(fs.pdf);
    x1.si.wi = x1.si.to_local(c.form.direction_from_reference_camera(sensor.to_sensor(p_cam)));
    WarRule rule{c, rng, x1.material, Vec3<Var>(ray.d), {}};
    return trace_path<Var>(c.scene, sampler, ray, first, x1.si, rule, c.settings, rays) * factor;
}

// ṡ · across at a point s of a pixel edge or of the film's edge: the film velocity
// d/dθ s(X(p + (θ − θ0) v(p), θ)) of the reparameterized first vertex p seen through s (material motion,
// moving camera and warp), for the flux −∮ P_j L (ṡ · n_out) over the edges where the filters jump
// (diff/pixel_boundary.h): the divergence theorem of Eq. 34 at p_1 with a field that does not vanish where
// s(p_1) crosses them; for the environment seen directly, the film velocity of its warped direction
// (escaped_first_vertex). The auxiliary stream is the edge sample's own.
Var film_edge_velocity(const WarScene& c, uint64_t seed, const Vec2f& s, const Vec2f& across,
                       uint64_t stream, RayCounter& rays) {
    const Sensor& sensor = *c.scene.sensor;
    const Ray ray = sensor.sample_ray(s, Vec2f(0.5f)).first;
    ++rays.rays;
    const SurfaceInteraction3f first = c.scene.intersect(ray);
    AuxiliaryRng rng(seed ^ 0x5851F42D4C957F2DULL, stream, 0, WarSalt);
    if (!first.is_valid()) {
        EscapedFirstVertex x1;
        if (!escaped_first_vertex(c, ray, rng, rays.rays, x1)) return Var(0.f);
        return (x1.s.x - Var(s.x)) * Var(across.x) + (x1.s.y - Var(s.y)) * Var(across.y);
    }
    const WarNeighbor camera{Interaction3f{Infinity, ray.o, Vec3f(0.f)}, c.form.camera_position(ray.o)};
    const WarVertex x1 = war_vertex(c, first, camera, rng, rays.rays);
    Vec2<Var> st;
    Var jacobian;
    if (!sensor.film_position(c.form.to_reference_camera(x1.si.p, ray.o),
                              c.form.direction_to_reference_camera(x1.si.n), st, jacobian))
        return Var(0.f);
    return (st.x - Var(s.x)) * Var(across.x) + (st.y - Var(s.y)) * Var(across.y);
}

// The flux across the edges where the filters jump: diff/pixel_boundary.h with the film velocity of the
// warped first vertex seen at the edge point.
PixelBoundary war_film_edge_term(const WarScene& c, uint64_t seed, int spp) {
    return PixelBoundary(
        c.scene,
        [&c, seed](const Vec2f& s, const Vec2f& across, uint64_t stream, RayCounter& rays) {
            return film_edge_velocity(c, seed, s, across, stream, rays);
        },
        film_edge_strata(*c.scene.sensor->film, spp));
}

// "warped-area reparameterization (unidirectional), N_q = 64, sigma = 0.006, alpha = 3, spread = 0.012,
// antithetic".
std::string describe_war(const WarFieldOptions& f, bool bidirectional) {
    char text[160];
    std::snprintf(text, sizeof(text),
                  "warped-area reparameterization (%s), N_q = %d, sigma = %g, alpha = %g, spread = %g%s",
                  bidirectional ? "bidirectional" : "unidirectional", f.aux_count, double(f.sigma),
                  double(f.exponent), double(f.spread), f.antithetic ? ", antithetic" : "");
    return text;
}

} // namespace

void set_war_samples(PixelLoop& loop, std::shared_ptr<const WarScene> field, WarSample sample,
                     const std::string& method) {
    loop.tiles =
        per_sample([sample = std::move(sample)](Sampler& sampler, const PixelSample& s, RayCounter& rays) {
            AuxiliaryRng rng(s.seed, s.pixel, uint64_t(s.m), WarSalt);
            return sample(sampler, rng, s.x, s.y, rays);
        });
    loop.film_edge = [field, spp = loop.options.spp](uint64_t seed) { return war_film_edge_term(*field, seed, spp); };
    loop.unwarped_delta_lights = method;
    loop.description = describe_war(field->options, method == "war-bdpt");
    loop.term = "warped-area";
}

void require_war_support(const Scene& scene, const Parameters& params) {
    require_film(scene, params);
    if (scene_has_media(scene))
        throw Error(
            "method war (paper 000) differentiates surfaces only and the scene has participating media: "
            "use the psdr method (the default)");
    if (!scene.sensor->projects_points())
        throw Error(
            "method war needs a sensor with one center of projection (perspective, orthographic, "
            "thinlens with aperture 0): its first vertex's field is conditioned on the camera's position");
    require_no_moving_edges_behind_delta_lobes(scene, params, "war");
}

DerivativeImage war_derivative(const Scene& scene, const Parameters& params, const WarOptions& options) {
    require_war_support(scene, params);
    return pixel_derivative(war_loop<WarContext>(scene, params, options, "war", camera_sample));
}

Gradient war_gradient(const Scene& scene, const Parameters& params, const Image& adjoint,
                      const WarOptions& options) {
    require_war_support(scene, params);
    return pixel_gradient(war_loop<WarContext>(scene, params, options, "war", camera_sample), adjoint);
}

} // namespace penumbra
