#include "diff/paths/path_sampling.h"

#include "core/batch_stats.h"
#include "core/interrupt.h"
#include "core/seconds.h"
#include "diff/paths/adaptive_pixels.h"
#include "diff/pixel_driver.h"
#include "render/tiles.h"

#include <atomic>
#include <chrono>
#include <cmath>

namespace penumbra {

namespace {

enum class Mode { Primal, Forward, Reverse };

// Pass 3 in forward mode: the tangent of the local value along params.direction(), times its weight.
struct ForwardSink {
    const float* direction;
    std::vector<float> tangent;
    Vec3d derivative{0.0};
    void operator()(const Color3<Var>& value, const Vec3d& weight) {
        Tape::current().forward(direction, tangent);
        const auto t = [&](const Var& v) { return v.id < 0 ? 0.0 : double(tangent[size_t(v.id)]); };
        derivative += Vec3d(weight.x * t(value.x), weight.y * t(value.y), weight.z * t(value.z));
    }
};

// Pass 3 in reverse mode: the weight is the adjoint of the local value (Algorithm 1, line 29).
struct ReverseSink {
    double* gradient;
    std::vector<float> scratch;
    std::vector<std::pair<int32_t, float>> seeds = std::vector<std::pair<int32_t, float>>(3);
    uint64_t dropped = 0; // local values whose adjoint sweep was not finite
    void operator()(const Color3<Var>& value, const Vec3d& weight) {
        seeds[0] = {value.x.id, float(weight.x)};
        seeds[1] = {value.y.id, float(weight.y)};
        seeds[2] = {value.z.id, float(weight.z)};
        dropped += !Tape::current().backward(seeds, gradient, scratch);
    }
};

struct PassResult {
    Image primal, derivative;
    std::vector<double> gradient;
    uint64_t dropped = 0; // the NaN policy's count
};

bool finite(const Vec3d& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// The film sample of path m of a pixel (filter importance sampling, as the renderer): the camera ray and its weight.
std::pair<Ray, Color3f> camera_sample(const Sensor& sensor, Sampler& sampler, int x, int y) {
    return sensor.sample_ray(sensor.film->sample_position(x, y, sampler.next_2d()), sampler.next_2d());
}

// One pass over the film: pixel j draws budget.count(j) paths, each weighted by 1 / c_j. Primal: pass 2 only;
// forward / reverse: passes 2 and 3 per path (the replay restarts the path's random stream).
PassResult run_pass(const Scene& scene, const Parameters& params, const PathSamplingSettings& settings,
                    const PixelBudget& budget, uint64_t seed, int threads, Mode mode, const Image* adjoint,
                    const std::function<void(float)>& progress) {
    const Sensor& sensor = *scene.sensor;
    const int width = sensor.film->width, height = sensor.film->height;
    PassResult out{Image(width, height), Image(width, height), std::vector<double>(size_t(params.dimension()), 0.0)};
    constexpr int tile = 16; // as for_each_tile
    const int tiles_x = (width + tile - 1) / tile, tiles_y = (height + tile - 1) / tile;
    // Per-tile gradients summed in tile order: the same result for any thread count.
    std::vector<std::vector<double>> tile_gradients(mode == Mode::Reverse ? size_t(tiles_x * tiles_y) : 0,
                                                    std::vector<double>(size_t(params.dimension()), 0.0));
    std::atomic<uint64_t> out_dropped{0};
    for_each_tile(width, height, threads, [&](int x0, int y0, int x1, int y1) {
        Sampler sampler;
        RayCounter rays;
        uint64_t dropped = 0;
        NoSink none;
        ForwardSink forward{params.direction().data(), {}, Vec3d(0.0)};
        ReverseSink reverse{mode == Mode::Reverse ? tile_gradients[size_t((y0 / tile) * tiles_x + x0 / tile)].data() : nullptr,
                            {}};
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                const uint64_t pixel = uint64_t(y) * width + x;
                const int n = budget.count(seed, pixel);
                if (n == 0) continue;
                const double c = budget.expected[pixel];
                const Vec3d a = adjoint ? Vec3d(adjoint->at(x, y)) : Vec3d(1.0);
                Vec3d primal(0.0), derivative(0.0);
                for (int m = 0; m < n; ++m) {
                    check_interrupt(); // per sample: at a large spp, a pixel takes seconds
                    sampler.start(seed, pixel, uint64_t(m));
                    const auto [ray, ray_weight] = camera_sample(sensor, sampler, x, y);
                    const Vec3d L = sample_path(scene, sampler, ray, settings, Vec3d(0.0), Vec3d(0.0), none, rays);
                    if (!finite(L)) {
                        ++dropped;
                        continue;
                    }
                    const Vec3d camera(ray_weight);
                    primal += L * camera;
                    if (mode == Mode::Primal) continue;
                    // Pass 3: the same path again (same random numbers).
                    sampler.start(seed, pixel, uint64_t(m));
                    const auto replayed = camera_sample(sensor, sampler, x, y);
                    if (mode == Mode::Forward) {
                        forward.derivative = Vec3d(0.0);
                        sample_path(scene, sampler, replayed.first, settings, L, camera, forward, rays);
                        if (finite(forward.derivative)) derivative += forward.derivative;
                        else ++dropped;
                    } else {
                        sample_path(scene, sampler, replayed.first, settings, L, a * camera / c, reverse, rays);
                    }
                }
                out.primal.at(x, y) = Color3f(primal / c);
                out.derivative.at(x, y) = Color3f(derivative / c);
            }
        Tape::current().clear();
        out_dropped += dropped + reverse.dropped;
    }, progress);
    out.dropped = out_dropped.load();
    for (const std::vector<double>& g : tile_gradients)
        for (size_t k = 0; k < g.size(); ++k) out.gradient[k] += g[k];
    return out;
}

PathSamplingSettings settings_of(const PathSamplingOptions& o) { return {o.path, o.differential, o.q, o.nee}; }

uint64_t batch_seed(uint64_t seed, int batch) { return seed + 0x9E3779B97F4A7C15ULL * uint64_t(batch); }

std::function<void(float)> batch_progress(const PathSamplingOptions& o, int batch) {
    if (!o.progress) return nullptr;
    return [&o, batch](float f) { o.progress((float(batch) + f) / float(o.batches)); };
}

void check_size(const Scene& scene, const Image& image, const char* what) {
    const Film& film = *scene.sensor->film;
    if (image.width != film.width || image.height != film.height)
        throw Error(std::string(what) + " is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                    ", the film " + std::to_string(film.width) + "x" + std::to_string(film.height));
}

// The mean over batches of a gradient vector.
std::vector<double> batch_mean(const std::vector<std::vector<double>>& batches) {
    const size_t B = batches.size(), dim = batches.front().size();
    std::vector<double> mean(dim, 0.0);
    for (const auto& g : batches)
        for (size_t k = 0; k < dim; ++k) mean[k] += g[k] / double(B);
    return mean;
}

// "differential sampling + NEE + adaptive pixels".
std::string describe(const PathSamplingOptions& o) {
    return std::string(o.differential ? "differential" : "bsdf") + " sampling" + (o.nee ? " + NEE" : "") +
           (o.adaptive ? " + adaptive pixels" : "");
}

} // namespace

void check_path_sampling(const Scene& scene, const Parameters& params, const PathSamplingOptions& o) {
    if (params.dimension() == 0) throw Error("no parameter is enabled for differentiation");
    if (!scene.sensor || !scene.sensor->film) throw Error("the scene has no sensor");
    require_no_media(scene);
    for (const auto& [p, index] : params.enabled())
        if (p->kind != Parameter::Kind::Data || p->geometry)
            throw Error("path sampling (paper 002) differentiates only parameters that do not move geometry; '" + p->name +
                        "' does (use the interior or psdr estimators)");
    if (o.spp <= 0 || o.batches <= 0) throw Error("path sampling: spp and batches must be positive");
    if (!(o.q >= 0.f && o.q < 1.f)) throw Error("path sampling: q must be in [0, 1), got " + std::to_string(o.q));
}

DerivativeImage path_sampling_derivative(const Scene& scene, const Parameters& params, const PathSamplingOptions& o,
                                         const Image& adjoint) {
    check_path_sampling(scene, params, o);
    const Film& film = *scene.sensor->film;
    if (o.adaptive) check_size(scene, adjoint, "the adjoint image for adaptive pixel sampling");
    const auto start = std::chrono::steady_clock::now();
    const PixelBudget budget = o.adaptive ? adaptive_budget(adjoint, o.spp, o.defensive) : uniform_budget(film.width, film.height, o.spp);
    ImageBatches primal, derivative;
    SampleCost cost;
    for (int b = 0; b < o.batches; ++b) {
        const PassResult r = run_pass(scene, params, settings_of(o), budget, batch_seed(o.seed, b), o.threads, Mode::Forward,
                                      nullptr, batch_progress(o, b));
        primal.add(r.primal);
        derivative.add(r.derivative);
        cost.dropped += r.dropped;
    }
    DerivativeImage d;
    d.derivative = derivative.mean();
    d.stderr_img = derivative.standard_error();
    d.mean_stderr = derivative.mean_standard_error();
    d.block_stderr = derivative.block_standard_errors();
    d.primal = primal.mean();
    d.description = "path sampling: " + describe(o);
    d.seconds = seconds_since(start);
    d.cost = cost;
    return d;
}

Gradient path_sampling_gradient(const Scene& scene, const Parameters& params, const Image& adjoint,
                                const PathSamplingOptions& o) {
    check_path_sampling(scene, params, o);
    check_size(scene, adjoint, "the adjoint image");
    const Film& film = *scene.sensor->film;
    const auto start = std::chrono::steady_clock::now();
    const PixelBudget budget = o.adaptive ? adaptive_budget(adjoint, o.spp, o.defensive) : uniform_budget(film.width, film.height, o.spp);
    std::vector<std::vector<double>> gradients;
    ImageBatches primal;
    Gradient g;
    for (int b = 0; b < o.batches; ++b) {
        PassResult r = run_pass(scene, params, settings_of(o), budget, batch_seed(o.seed, b), o.threads, Mode::Reverse,
                                &adjoint, batch_progress(o, b));
        gradients.push_back(std::move(r.gradient));
        primal.add(r.primal);
        g.cost.dropped += r.dropped;
    }
    g.values = batch_mean(gradients);
    g.batch_values = std::move(gradients);
    g.primal = primal.mean();
    g.description = "paths: " + describe(o);
    g.seconds = seconds_since(start);
    return g;
}

Gradient path_sampling_loss_gradient(const Scene& scene, const Parameters& params, const Image& target,
                                     LossKind loss, const PathSamplingOptions& o) {
    check_path_sampling(scene, params, o);
    check_size(scene, target, "the target image");
    if (!(o.primal_fraction > 0.0 && o.primal_fraction < 1.0))
        throw Error("path sampling: primal_fraction must be in (0, 1), got " + std::to_string(o.primal_fraction));
    const int spp_primal = std::max(1, int(std::lround(o.spp * o.primal_fraction)));
    const double spp_gradient = double(o.spp - spp_primal);
    if (!(spp_gradient > 0.0))
        throw Error("path sampling: --spp " + std::to_string(o.spp) + " leaves no sample for the gradient passes after " +
                    std::to_string(spp_primal) + " primal samples per pixel");
    const Film& film = *scene.sensor->film;
    const auto start = std::chrono::steady_clock::now();
    Gradient out;
    out.loss = 0;
    std::vector<std::vector<double>> gradients;
    for (int b = 0; b < o.batches; ++b) {
        const uint64_t seed = batch_seed(o.seed, b);
        // Pass 1: its own random numbers, so that ∂L/∂I is independent of passes 2-3 (unbiased for losses
        // whose adjoint is affine in I, such as L2).
        const PassResult first = run_pass(scene, params, settings_of(o), uniform_budget(film.width, film.height, spp_primal),
                                          seed ^ 0x5DEECE66DULL, o.threads, Mode::Primal, nullptr, nullptr);
        const LossResult l = compute_loss(loss, first.primal, target);
        const PixelBudget budget = o.adaptive ? adaptive_budget(l.adjoint, spp_gradient, o.defensive)
                                              : uniform_budget(film.width, film.height, spp_gradient);
        PassResult r = run_pass(scene, params, settings_of(o), budget, seed, o.threads, Mode::Reverse,
                                &l.adjoint, batch_progress(o, b));
        gradients.push_back(std::move(r.gradient));
        out.loss += l.value / double(o.batches);
        out.primal = first.primal;
    }
    out.values = batch_mean(gradients);
    out.batch_values = std::move(gradients);
    out.description = "paths: " + describe(o);
    out.seconds = seconds_since(start);
    return out;
}

} // namespace penumbra
