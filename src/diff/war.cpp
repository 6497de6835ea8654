#include "diff/war.h"

#include "core/batch_stats.h"
#include "core/interrupt.h"
#include "diff/film_sample.h"
#include "diff/material_form.h"
#include "diff/pixel_boundary.h"
#include "render/emitter_hit.h"
#include "render/light_medium.h"
#include "render/mis.h"
#include "render/tiles.h"

#include <tbb/enumerable_thread_specific.h>

#include <chrono>

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

    WarContext(const Scene& s, const Parameters& p, const WarOptions& o)
        : scene(s), params(p), form(s, p, FirstVertex::Material),
          boundary(s), field{s, p, form, boundary, o.field}, settings(o.path) {}
};

// The radiance of the infinite emitters along the escaped direction d warped on the sphere (value d, tangent
// V).
Color3<Var> environment(const WarContext& c, const Vec3f& d, const Vec3<Var>& warped) {
    Color3<Var> L(Var(0.f));
    for (const auto& e : c.scene.emitters)
        if (e->is_infinite() && !e->is_delta())
            L += e->eval_environment(c.form.direction_to_reference_light(*e, d) + (warped - Vec3<Var>(d)));
    return L;
}

// Next-event estimation at the detector vertex p^D_n (Algorithm 2 lines 7–10): the light vertex p^S_n warped
// conditioned on p^D_n, f_s L_e G J (1 + ∇·v) / (G_0 p_σ); the environment's direction warped on the sphere;
// delta lights connected in material form without a warp.
Color3<Var> next_event(const WarContext& c, const BSDF* bsdf, const SurfaceInteraction3f& hit,
                       const SurfaceInteraction<Var>& si, const WarNeighbor& here,
                       const DirectionSample3f& ds, WarRng& rng, uint64_t& rays) {
    const BSDFContext ctx{TransportMode::Radiance};
    if (ds.emitter->is_delta()) return next_event_contribution(ctx, bsdf, si, ds, c.form);
    if (const Shape* shape = ds.emitter->shape()) {
        const SurfaceInteraction3f light =
            surface_interaction<float>(*shape, ds.prim, ds.bary, MeshVertices{shape->mesh});
        WarVertex y = war_vertex(c.field, light, here, rng, rays);
        const Vec3<Var> to_light = y.si.p - si.p;
        const Var dist2 = squared_norm(to_light);
        const Vec3<Var> wo = to_light / sqrt(dist2);
        y.si.wi = y.si.to_local(-wo);
        const Var g = abs(dot(y.si.n, wo)) / dist2;
        return bsdf->eval(ctx, si, si.to_local(wo)) * ds.emitter->eval(y.si) *
               (relative_change(g * y.jacobian) / Var(ds.pdf));
    }
    const WarpEstimate e = war_direction(c.field, hit, here.position, ds.d, rng, rays);
    return bsdf->eval(ctx, si, si.to_local(e.direction)) * (e.jacobian / Var(ds.pdf)) *
           ds.emitter->eval_environment(c.form.direction_to_reference_light(*ds.emitter, ds.d) +
                                        (e.direction - Vec3<Var>(ds.d)));
}

// The radiance leaving the first vertex toward the camera along one path (render/path_tracer.h's sampling in
// the reference configuration; Algorithm 2 lines 6–17), every vertex warped as it is sampled.
Color3<Var> warped_path(const WarContext& c, Sampler& sampler, WarRng& rng, const Ray& primary,
                        const SurfaceInteraction3f& first, const WarVertex& first_vertex, uint64_t& rays) {
    const BSDFContext ctx{TransportMode::Radiance};
    const PathSettings& settings = c.settings;
    Color3<Var> L(Var(0.f)), throughput(Var(1.f));
    if (settings.max_depth == 0) return L;
    const unsigned max_depth = unsigned(settings.max_depth); // -1 wraps to "infinite"
    float eta = 1.f;
    Ray ray = primary;
    SurfaceInteraction3f hit = first, prev_hit;
    SurfaceInteraction<Var> si = first_vertex.si;
    Vec3<Var> material = first_vertex.material, escaped(ray.d);
    float prev_bsdf_pdf = 1.f;
    bool prev_bsdf_delta = true;

    for (unsigned depth = 0;; ++depth) {
        if (!(depth == 0 && settings.hide_emitters))
            for_each_emitter_hit(
                c.scene, prev_hit, ray.d, hit, [&](const Emitter* e, const Color3f&, float pdf) {
                    const float w = prev_bsdf_delta ? 1.f : mis_power(prev_bsdf_pdf, pdf);
                    const Color3<Var> Le = hit.is_valid() ? e->eval(si) : environment(c, ray.d, escaped);
                    L += throughput * Le * Var(w);
                });
        if (!hit.is_valid() || depth + 1 >= max_depth) break;
        const BSDF* bsdf = hit.bsdf();
        if (!bsdf) break;
        const WarNeighbor here{hit, material};

        if (bsdf->has(BSDFSmooth) && !c.scene.emitters.empty()) {
            const auto [ds, em_weight] = c.scene.sample_emitter_direction(hit, sampler.next_2d(), true);
            ++rays;
            if (!is_black(em_weight)) {
                const float w = ds.delta ? 1.f : mis_power(ds.pdf, bsdf->pdf(ctx, hit, hit.to_local(ds.d)));
                L += throughput * next_event(c, bsdf, hit, si, here, ds, rng, rays) * Var(w);
            }
        } else {
            sampler.next_2d(); // keep the sample stream aligned across materials
        }

        const float u1 = sampler.next_1d();
        const auto [bs, weight] = bsdf->sample(ctx, hit, u1, sampler.next_2d());
        if (is_black(weight)) break;
        const Vec3f d = hit.to_world(bs.wo);
        ray = hit.spawn_ray(d);
        ++rays;
        const SurfaceInteraction3f next = c.scene.intersect(ray);
        const bool delta = (bs.sampled_type & BSDFDelta) != 0;
        SurfaceInteraction<Var> next_si;
        if (delta) {
            // No area integral at a delta lobe: the direction is fixed, no derivative flows through it.
            throughput *= Color3<Var>(weight);
            if (next.is_valid()) next_si = c.form.vertex(next), material = next_si.p;
            escaped = Vec3<Var>(d);
        } else if (next.is_valid()) {
            // p^D_{n+1} warped conditioned on p^D_n: f_s G J (1 + ∇·v) / (G_0 p_σ).
            const WarVertex x = war_vertex(c.field, next, here, rng, rays);
            const Vec3<Var> to_next = x.si.p - si.p;
            const Var dist2 = squared_norm(to_next);
            const Vec3<Var> wo = to_next / sqrt(dist2);
            const Var g = abs(dot(x.si.n, wo)) / dist2;
            throughput *=
                bsdf->eval(ctx, si, si.to_local(wo)) * (relative_change(g * x.jacobian) / Var(bs.pdf));
            next_si = x.si;
            material = x.material;
        } else {
            const WarpEstimate e = war_direction(c.field, hit, material, d, rng, rays);
            throughput *= bsdf->eval(ctx, si, si.to_local(e.direction)) * (e.jacobian / Var(bs.pdf));
            escaped = e.direction;
        }
        if (next.is_valid()) {
            next_si.wi = next_si.to_local(normalize(si.p - next_si.p));
            si = next_si;
        }
        eta *= bs.eta;
        prev_hit = hit;
        prev_bsdf_pdf = bs.pdf;
        prev_bsdf_delta = delta;
        hit = next;
        if (depth + 1 >= unsigned(settings.rr_depth) && !survives_roulette(throughput, eta, sampler)) break;
    }
    return L;
}

// One camera sample of pixel (px, py): the film position from the defensive filter mixture
// (diff/film_sample.h), the first vertex p^D_1 warped conditioned on the camera, and the camera factor
// P_j(s(x1(θ))) |ds/dA|(θ) J (1 + ∇·v) / (p_s |ds/dA|(θ0)) of the material-form first vertex (paper 001).
Color3<Var> camera_sample(const WarContext& c, Sampler& sampler, WarRng& rng, int px, int py,
                          uint64_t& rays) {
    const Sensor& sensor = *c.scene.sensor;
    const Film& film = *sensor.film;
    const FilmSample fs = sample_film(*film.rfilter, sampler, false);
    const Vec2f center(px + 0.5f, py + 0.5f);
    const auto [ray, ray_weight] = sensor.sample_ray(center + fs.offset, sampler.next_2d());
    ++rays;
    const SurfaceInteraction3f first = c.scene.intersect(ray);
    if (!first.is_valid()) {
        const float w = film.filter_weight(px, py, center + fs.offset) / fs.pdf;
        return c.settings.hide_emitters ? Color3<Var>(Var(0.f))
                                        : c.form.environment(c.scene, ray.d) * Color3<Var>(ray_weight * w);
    }
    const WarNeighbor camera{Interaction3f{Infinity, ray.o, Vec3f(0.f)}, c.form.camera_position(ray.o)};
    WarVertex x1 = war_vertex(c.field, first, camera, rng, rays);
    const Vec3<Var> p_cam = c.form.to_reference_camera(x1.si.p, ray.o);
    const Vec3<Var> n_cam = c.form.direction_to_reference_camera(x1.si.n);
    Vec2<Var> s;
    Var jacobian;
    if (!sensor.film_position(p_cam, n_cam, s, jacobian)) return Color3<Var>(Var(0.f));
    const Var factor = film.filter_weight(px, py, s) * relative_change(jacobian * x1.jacobian) / Var(fs.pdf);
    x1.si.wi = x1.si.to_local(c.form.direction_from_reference_camera(sensor.to_sensor(p_cam)));
    return warped_path(c, sampler, rng, ray, first, x1, rays) * factor;
}

// ṡ · across at a point s of a pixel edge or of the film's edge: the film velocity
// d/dθ s(X(p + (θ − θ0) v(p), θ)) of the reparameterized first vertex p seen through s (material motion,
// moving camera and warp), for the flux −∮ P_j L (ṡ · n_out) over the edges where the filters jump
// (diff/pixel_boundary.h): the divergence theorem of Eq. 34 at p_1 with a field that does not vanish where
// s(p_1) crosses them. Zero for the environment seen directly (its film position does not move:
// camera_sample). The auxiliary stream is the edge sample's own.
Var film_edge_velocity(const WarScene& c, uint64_t seed, const Vec2f& s, const Vec2f& across,
                       uint64_t stream, RayCounter& rays) {
    const Sensor& sensor = *c.scene.sensor;
    const Ray ray = sensor.sample_ray(s, Vec2f(0.5f)).first;
    ++rays.rays;
    const SurfaceInteraction3f first = c.scene.intersect(ray);
    if (!first.is_valid()) return Var(0.f);
    WarRng rng(seed ^ 0x5851F42D4C957F2DULL, stream, 0);
    const WarNeighbor camera{Interaction3f{Infinity, ray.o, Vec3f(0.f)}, c.form.camera_position(ray.o)};
    const WarVertex x1 = war_vertex(c, first, camera, rng, rays.rays);
    Vec2<Var> st;
    Var jacobian;
    if (!sensor.film_position(c.form.to_reference_camera(x1.si.p, ray.o),
                              c.form.direction_to_reference_camera(x1.si.n), st, jacobian))
        return Var(0.f);
    return (st.x - Var(s.x)) * Var(across.x) + (st.y - Var(s.y)) * Var(across.y);
}

} // namespace

// About `spp` samples per pixel whose filter jumps at its own edges (box: ~2 unit segments per pixel), `spp`
// per unit of the film's edge otherwise.
PixelBoundary war_film_edge_term(const WarScene& c, uint64_t seed, int spp) {
    const bool box = c.scene.sensor->film->rfilter->plugin == "box";
    return PixelBoundary(
        c.scene,
        [&c, seed](const Vec2f& s, const Vec2f& across, uint64_t stream, RayCounter& rays) {
            return film_edge_velocity(c, seed, s, across, stream, rays);
        },
        box ? std::max(1, spp / 2) : spp);
}

BoundaryOptions war_film_edge_options(const WarOptions& options, uint64_t seed, SampleCost& cost) {
    BoundaryOptions bo;
    bo.seed = seed;
    bo.threads = options.threads;
    bo.path = options.path;
    bo.first_vertex = FirstVertex::Material;
    bo.cost = &cost;
    return bo;
}

namespace {

bool finite(const Color3<Var>& v) {
    return std::isfinite(v.x.v) && std::isfinite(v.y.v) && std::isfinite(v.z.v);
}
float tangent_of(const Var& v, const std::vector<float>& tangent) { return v.id < 0 ? 0.f : tangent[v.id]; }

struct PixelSums {
    Image primal, derivative;
};

// One batch of the forward-mode estimator. Random numbers depend only on (seed, pixel, sample): tiles and
// threads do not change them.
PixelSums forward_batch(const WarContext& c, const WarOptions& options, uint64_t seed,
                        const std::function<void(float)>& progress, SharedSampleCost& cost) {
    const Film& film = *c.scene.sensor->film;
    PixelSums out{Image(film.width, film.height), Image(film.width, film.height)};
    for_each_tile(
        film.width, film.height, options.threads,
        [&](int x0, int y0, int x1, int y1) {
            Sampler sampler(*c.scene.sensor->sampler, options.spp);
            uint64_t rays = 0, tape_nodes = 0;
            std::vector<float> tangent;
            Tape& tape = Tape::current();
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) {
                    check_interrupt();
                    const uint64_t pixel = uint64_t(y) * film.width + x;
                    Vec3d primal(0.0), derivative(0.0);
                    for (int m = 0; m < options.spp; ++m) {
                        sampler.start(seed, pixel, uint64_t(m));
                        WarRng rng(seed, pixel, uint64_t(m));
                        tape.clear();
                        const Color3<Var> v = camera_sample(c, sampler, rng, x, y, rays);
                        tape_nodes += tape.size();
                        if (!finite(v)) continue;
                        tape.forward(c.params.direction().data(), tangent);
                        primal += Vec3d(v.x.v, v.y.v, v.z.v);
                        const Vec3d d(tangent_of(v.x, tangent), tangent_of(v.y, tangent),
                                      tangent_of(v.z, tangent));
                        if (is_finite(Vec3f(d))) derivative += d;
                    }
                    out.primal.at(x, y) = Color3f(primal / double(options.spp));
                    out.derivative.at(x, y) = Color3f(derivative / double(options.spp));
                }
            tape.clear();
            cost.add({uint64_t(x1 - x0) * uint64_t(y1 - y0) * uint64_t(options.spp), rays, tape_nodes});
        },
        progress);
    return out;
}

} // namespace

void require_war_support(const Scene& scene, const Parameters& params) {
    if (params.dimension() == 0) throw Error("no parameter is enabled for differentiation");
    if (!scene.sensor || !scene.sensor->film) throw Error("the scene has no sensor");
    if (scene_has_media(scene))
        throw Error(
            "method war (paper 000) differentiates surfaces only and the scene has participating media: "
            "use the psdr method (the default)");
    if (!scene.sensor->projects_points())
        throw Error(
            "method war needs a sensor with one center of projection (perspective, orthographic, "
            "thinlens with aperture 0): its first vertex's field is conditioned on the camera's position");
}

DerivativeImage war_derivative(const Scene& scene, const Parameters& params, const WarOptions& options) {
    require_war_support(scene, params);
    if (options.spp <= 0 || options.batches <= 0) throw Error("derivative: spp and batches must be positive");
    const auto start = std::chrono::steady_clock::now();
    const WarContext c(scene, params, options);
    const int B = options.batches;
    ImageBatches primal, derivative;
    SharedSampleCost cost;
    for (int b = 0; b < B; ++b) {
        auto progress = options.progress
                            ? std::function<void(float)>([&, b](float f) { options.progress((b + f) / B); })
                            : std::function<void(float)>();
        const uint64_t seed = options.seed + 0x9E3779B97F4A7C15ULL * uint64_t(b);
        PixelSums s = forward_batch(c, options, seed, progress, cost);
        SampleCost edge_cost;
        const Image edges = war_film_edge_term(c.field, seed, options.spp)
                                .derivative(params, war_film_edge_options(options, seed, edge_cost));
        cost.add({0, edge_cost.rays, edge_cost.tape_nodes});
        for (size_t i = 0; i < edges.pixels.size(); ++i)
            s.derivative.pixels[i] += edges.pixels[i];
        primal.add(s.primal);
        derivative.add(s.derivative);
    }
    DerivativeImage result{primal.mean(), derivative.mean(), derivative.standard_error(), 0.0, cost.get()};
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

Gradient war_gradient(const Scene& scene, const Parameters& params, const Image& adjoint,
                      const WarOptions& options) {
    require_war_support(scene, params);
    const Film& film = *scene.sensor->film;
    check_adjoint_size(film, adjoint);
    if (options.spp <= 0) throw Error("gradient: spp must be positive");
    const auto start = std::chrono::steady_clock::now();
    const WarContext c(scene, params, options);
    const size_t dim = size_t(params.dimension());
    tbb::enumerable_thread_specific<std::vector<double>> gradients(
        [dim] { return std::vector<double>(dim, 0.0); });
    Gradient result{std::vector<double>(dim, 0.0), {}, Image(film.width, film.height), 0.0, {}};
    for (const auto& e : scene.emitters)
        if (e->is_delta() && !e->is_infinite()) {
            result.warnings.push_back(
                "method war does not see the motion of shadows cast from point and spot lights");
            break;
        }
    const float inv_spp = 1.f / float(options.spp);
    SharedSampleCost cost;
    for_each_tile(
        film.width, film.height, options.threads,
        [&](int x0, int y0, int x1, int y1) {
            Sampler sampler(*scene.sensor->sampler, options.spp);
            uint64_t rays = 0, tape_nodes = 0;
            std::vector<float> scratch;
            std::vector<std::pair<int32_t, float>> seeds(3);
            std::vector<double>& gradient = gradients.local();
            Tape& tape = Tape::current();
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) {
                    check_interrupt();
                    const uint64_t pixel = uint64_t(y) * film.width + x;
                    const Color3f a = adjoint.at(x, y) * inv_spp;
                    Vec3d primal(0.0);
                    for (int m = 0; m < options.spp; ++m) {
                        sampler.start(options.seed, pixel, uint64_t(m));
                        WarRng rng(options.seed, pixel, uint64_t(m));
                        tape.clear();
                        const Color3<Var> v = camera_sample(c, sampler, rng, x, y, rays);
                        tape_nodes += tape.size();
                        if (!finite(v)) continue;
                        primal += Vec3d(v.x.v, v.y.v, v.z.v);
                        seeds[0] = {v.x.id, a.x};
                        seeds[1] = {v.y.id, a.y};
                        seeds[2] = {v.z.id, a.z};
                        tape.backward(seeds, gradient.data(), scratch);
                    }
                    result.primal.at(x, y) = Color3f(primal / double(options.spp));
                }
            tape.clear();
            cost.add({uint64_t(x1 - x0) * uint64_t(y1 - y0) * uint64_t(options.spp), rays, tape_nodes});
        },
        options.progress);
    std::vector<double> edges(dim, 0.0);
    SampleCost edge_cost;
    war_film_edge_term(c.field, options.seed, options.spp)
        .gradient(params, adjoint, war_film_edge_options(options, options.seed, edge_cost), edges);
    cost.add({0, edge_cost.rays, edge_cost.tape_nodes});
    for (size_t k = 0; k < dim; ++k)
        result.values[k] += edges[k];
    result.cost = cost.get();
    for (const std::vector<double>& g : gradients)
        for (size_t k = 0; k < dim; ++k)
            result.values[k] += g[k];
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

} // namespace penumbra
