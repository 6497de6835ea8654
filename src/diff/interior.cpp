#include "diff/interior.h"

#include "core/batch_stats.h"
#include "core/interrupt.h"
#include "core/stratified.h"
#include "diff/film_sample.h"
#include "diff/interior_media.h"
#include "diff/material_form.h"
#include "render/light_medium.h"
#include "render/bdpt.h"
#include "render/path.h"
#include "render/volpath.h"
#include "render/tiles.h"

#include <tbb/enumerable_thread_specific.h>

#include <chrono>

namespace penumbra {

PathSettings path_settings(const Scene& scene) {
    if (const auto* path = dynamic_cast<const PathIntegrator*>(scene.integrator.get())) return path->settings();
    if (const auto* volpath = dynamic_cast<const VolPathIntegrator*>(scene.integrator.get())) return volpath->settings();
    if (const auto* bdpt = dynamic_cast<const BidirectionalPathTracer*>(scene.integrator.get())) {
        const BDPTSettings& b = bdpt->settings();
        return PathSettings{b.max_depth, b.rr_depth, b.hide_emitters};
    }
    return PathSettings{};
}

namespace {

// One camera path of pixel (x, y) with the image-space first vertex: the film position is drawn by filter
// importance sampling, as the renderer does (stratified over the pixel's samples), and its ray stays fixed;
// x1(θ) slides along it with the surface (MaterialForm::ray_vertex). The camera factor W_j / p is the renderer's sample weight, independent of θ.
Color3<Var> sample_image_space(const Scene& scene, const MaterialForm& form, Sampler& sampler, int x, int y,
                               const PixelStratum& stratum, bool media, bool bidirectional, const PathSettings& settings,
                               RayCounter& rays) {
    const Sensor& sensor = *scene.sensor;
    const Vec2f pos = sensor.film->sample_position(x, y, stratum(sampler.next_2d()));
    const auto [ray, ray_weight] = sensor.sample_ray(pos, sampler.next_2d());
    ++rays.rays;
    if (bidirectional) return bidirectional_camera_path(scene, form, sampler, ray, ray_weight, {}, 1.f, settings, rays);
    if (media) return volumetric_camera_path(scene, form, sampler, ray, ray_weight, {}, 1.f, settings, rays);
    const SurfaceInteraction3f first = scene.intersect(ray);
    if (!first.is_valid())
        return settings.hide_emitters ? Color3<Var>(Var(0.f))
                                      : form.environment(scene, ray.d) * Color3<Var>(ray_weight);
    SurfaceInteraction<Var> x1 = form.ray_vertex(first, ray);
    x1.wi = x1.to_local(Vec3<Var>(ray.d * -1.f));
    return trace_path<Var>(scene, sampler, ray, first, x1, form, settings, rays) * Color3<Var>(ray_weight);
}

// One camera path of pixel (x, y) as a function of θ: W_j(x1(θ)) L(x1 → camera) / p, with the camera factor
// W_j / p = P_j(s(θ)) |ds/dA|(θ) J(p1) / (p_s |ds/dA|(θ0)) (the pinhole importance of Eqs. 22-23 written on the
// film, P_j the normalized reconstruction filter of pixel j, s the projection of x1).
Color3<Var> sample_contribution(const Scene& scene, const MaterialForm& form, Sampler& sampler, int x, int y,
                                const PixelStratum& stratum, bool mirror, bool media, bool bidirectional,
                                const PathSettings& settings, RayCounter& rays) {
    if (form.image_space_first_vertex())
        return sample_image_space(scene, form, sampler, x, y, stratum, media, bidirectional, settings, rays);
    const Sensor& sensor = *scene.sensor;
    const ReconstructionFilter& filter = *sensor.film->rfilter;
    const FilmSample fs = sample_film(filter, sampler, mirror);
    const Vec2f center(x + 0.5f, y + 0.5f);
    const auto [ray, ray_weight] = sensor.sample_ray(center + fs.offset, sampler.next_2d());
    ++rays.rays;
    const Vec3f camera = sensor.to_world.apply_point(Vec3f(0.f));
    if (media || bidirectional) {
        // W_j / p = P_j(s(θ)) |ds/dA|(θ) J / (p_s |ds/dA|(θ0)); a medium vertex's |ds/dA| has the normal
        // toward the camera (|ds/dω| / ℓ², the volume measure).
        const CameraFactor factor = [&](const Vec3<Var>& p, const Vec3<Var>& n, const Var& jacobian) {
            const Vec3<Var> p_cam = form.to_reference_camera(p, camera);
            Vec2<Var> s;
            Var film_jacobian;
            if (!sensor.film_position(p_cam, form.direction_to_reference_camera(n), s, film_jacobian)) return Var(0.f);
            return sensor.film->filter_weight(x, y, s) * relative_change(film_jacobian * jacobian) / Var(fs.pdf);
        };
        const float escaped = sensor.film->filter_weight(x, y, center + fs.offset) / fs.pdf;
        if (bidirectional)
            return bidirectional_camera_path(scene, form, sampler, ray, ray_weight, factor, escaped, settings, rays);
        return volumetric_camera_path(scene, form, sampler, ray, ray_weight, factor, escaped, settings, rays);
    }
    const SurfaceInteraction3f first = scene.intersect(ray);
    if (!first.is_valid()) {
        // The environment seen through the film is a direction: only its own rotation changes it.
        const float w = sensor.film->filter_weight(x, y, center + fs.offset) / fs.pdf;
        return settings.hide_emitters ? Color3<Var>(Var(0.f))
                                      : form.environment(scene, ray.d) * Color3<Var>(ray_weight * w);
    }

    SurfaceInteraction<Var> x1 = form.vertex(first);
    const Vec3<Var> p_cam = form.to_reference_camera(x1.p, camera);
    const Vec3<Var> n_cam = form.direction_to_reference_camera(x1.n);
    Vec2<Var> s;
    Var jacobian;
    if (!sensor.film_position(p_cam, n_cam, s, jacobian)) return Color3<Var>(Var(0.f));
    const Var P = sensor.film->filter_weight(x, y, s);
    const Var camera_factor = P * relative_change(jacobian * form.jacobian(first)) / Var(fs.pdf);

    x1.wi = x1.to_local(form.direction_from_reference_camera(sensor.to_sensor(p_cam)));
    return trace_path<Var>(scene, sampler, ray, first, x1, form, settings, rays) * camera_factor;
}

bool finite(const Color3<Var>& c) { return std::isfinite(c.x.v) && std::isfinite(c.y.v) && std::isfinite(c.z.v); }

float tangent_of(const Var& v, const std::vector<float>& tangent) { return v.id < 0 ? 0.f : tangent[v.id]; }

struct PixelSums {
    Image primal, derivative;
};

// One batch of the forward-mode estimator.
PixelSums forward_batch(const Scene& scene, const Parameters& params, const DiffOptions& options, uint64_t seed,
                        const std::function<void(float)>& progress, SharedSampleCost& cost) {
    const Film& film = *scene.sensor->film;
    PixelSums out{Image(film.width, film.height), Image(film.width, film.height)};
    const MaterialForm form(scene, params, options.first_vertex);
    const bool antithetic = options.antithetic && !form.image_space_first_vertex();
    const bool media = scene_has_media(scene);
    const bool bidirectional = bidirectional_interior(scene, options.estimator);
    const PathSettings settings = options.path;
    for_each_tile(film.width, film.height, options.threads, [&](int x0, int y0, int x1, int y1) {
        Sampler sampler(*scene.sensor->sampler, antithetic ? (options.spp + 1) / 2 : options.spp);
        RayCounter rays;
        uint64_t tape_nodes = 0;
        std::vector<float> tangent;
        Tape& tape = Tape::current();
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                check_interrupt(); // per pixel: Ctrl-C stops long renders promptly (core/interrupt.h)
                const uint64_t pixel = uint64_t(y) * film.width + x;
                Vec3d primal(0.0), derivative(0.0);
                for (int m = 0; m < options.spp; ++m) {
                    const bool mirror = antithetic && (m & 1);
                    sampler.start(seed, pixel, uint64_t(antithetic ? m / 2 : m));
                    tape.clear();
                    const PixelStratum stratum(m, options.spp, seed, pixel);
                    const Color3<Var> c = sample_contribution(scene, form, sampler, x, y, stratum, mirror, media, bidirectional, settings, rays);
                    tape_nodes += tape.size();
                    if (!finite(c)) continue;
                    tape.forward(params.direction().data(), tangent);
                    primal += Vec3d(c.x.v, c.y.v, c.z.v);
                    const Vec3d d(tangent_of(c.x, tangent), tangent_of(c.y, tangent), tangent_of(c.z, tangent));
                    if (is_finite(Vec3f(d))) derivative += d;
                }
                out.primal.at(x, y) = Color3f(primal / double(options.spp));
                out.derivative.at(x, y) = Color3f(derivative / double(options.spp));
            }
        tape.clear();
        cost.add({uint64_t(x1 - x0) * uint64_t(y1 - y0) * uint64_t(options.spp), rays.rays, tape_nodes});
    }, progress);
    return out;
}

void check_ready(const Scene& scene, const Parameters& params) {
    if (params.dimension() == 0) throw Error("no parameter is enabled for differentiation");
    if (!scene.sensor || !scene.sensor->film) throw Error("the scene has no sensor");
}

} // namespace

void require_no_media(const Scene& scene) {
    if (scene_has_media(scene))
        throw Error("the scene has participating media, which this method does not differentiate: use the psdr "
                    "method (the default)");
}

DerivativeImage render_derivative(const Scene& scene, const Parameters& params, const DiffOptions& options) {
    check_ready(scene, params);
    if (options.spp <= 0 || options.batches <= 0) throw Error("derivative: spp and batches must be positive");
    if (bidirectional_interior(scene, options.estimator)) require_bidirectional_support(scene);
    const auto start = std::chrono::steady_clock::now();
    const int B = options.batches;
    ImageBatches primal, derivative;
    SharedSampleCost cost;
    for (int b = 0; b < B; ++b) {
        auto progress = options.progress ? std::function<void(float)>([&, b](float f) { options.progress((b + f) / B); })
                                         : std::function<void(float)>();
        const PixelSums s = forward_batch(scene, params, options, options.seed + 0x9E3779B97F4A7C15ULL * uint64_t(b), progress, cost);
        primal.add(s.primal);
        derivative.add(s.derivative);
    }
    DerivativeImage result{primal.mean(), derivative.mean(), derivative.standard_error(), 0.0, cost.get()};
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

void check_adjoint_size(const Film& film, const Image& adjoint) {
    if (adjoint.width != film.width || adjoint.height != film.height)
        throw Error("gradient: the adjoint image is " + std::to_string(adjoint.width) + "x" +
                    std::to_string(adjoint.height) + ", the film " + std::to_string(film.width) + "x" +
                    std::to_string(film.height));
}

Gradient render_gradient(const Scene& scene, const Parameters& params, const Image& adjoint, const DiffOptions& options) {
    check_ready(scene, params);
    const Film& film = *scene.sensor->film;
    check_adjoint_size(film, adjoint);
    if (options.spp <= 0) throw Error("gradient: spp must be positive");
    const auto start = std::chrono::steady_clock::now();
    const MaterialForm form(scene, params, options.first_vertex);
    const bool antithetic = options.antithetic && !form.image_space_first_vertex();
    const bool media = scene_has_media(scene);
    const bool bidirectional = bidirectional_interior(scene, options.estimator);
    if (bidirectional) require_bidirectional_support(scene);
    const size_t dim = size_t(params.dimension());
    tbb::enumerable_thread_specific<std::vector<double>> gradients([dim] { return std::vector<double>(dim, 0.0); });
    Gradient result{std::vector<double>(dim, 0.0), {}, Image(film.width, film.height), 0.0, {}};
    for (const std::string& shape : form.volume_motion().omitted())
        result.warnings.push_back("the medium around '" + shape + "' does not follow its vertex_positions (" +
                                  "it touches another shape): their gradient misses the medium's motion");
    const float inv_spp = 1.f / float(options.spp);
    SharedSampleCost cost;

    for_each_tile(film.width, film.height, options.threads, [&](int x0, int y0, int x1, int y1) {
        Sampler sampler(*scene.sensor->sampler, antithetic ? (options.spp + 1) / 2 : options.spp);
        RayCounter rays;
        uint64_t tape_nodes = 0;
        std::vector<float> scratch;
        std::vector<std::pair<int32_t, float>> seeds(3);
        std::vector<double>& gradient = gradients.local();
        Tape& tape = Tape::current();
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                check_interrupt(); // per pixel: Ctrl-C stops long renders promptly (core/interrupt.h)
                const uint64_t pixel = uint64_t(y) * film.width + x;
                const Color3f a = adjoint.at(x, y) * inv_spp;
                Vec3d primal(0.0);
                for (int m = 0; m < options.spp; ++m) {
                    const bool mirror = antithetic && (m & 1);
                    sampler.start(options.seed, pixel, uint64_t(antithetic ? m / 2 : m));
                    tape.clear();
                    const PixelStratum stratum(m, options.spp, options.seed, pixel);
                    const Color3<Var> c = sample_contribution(scene, form, sampler, x, y, stratum, mirror, media, bidirectional, options.path, rays);
                    tape_nodes += tape.size();
                    if (!finite(c)) continue;
                    primal += Vec3d(c.x.v, c.y.v, c.z.v);
                    seeds[0] = {c.x.id, a.x};
                    seeds[1] = {c.y.id, a.y};
                    seeds[2] = {c.z.id, a.z};
                    tape.backward(seeds, gradient.data(), scratch);
                }
                result.primal.at(x, y) = Color3f(primal / double(options.spp));
            }
        tape.clear();
        cost.add({uint64_t(x1 - x0) * uint64_t(y1 - y0) * uint64_t(options.spp), rays.rays, tape_nodes});
    }, options.progress);
    result.cost = cost.get();

    for (const std::vector<double>& g : gradients)
        for (size_t k = 0; k < dim; ++k) result.values[k] += g[k];
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

} // namespace penumbra
