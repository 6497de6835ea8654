#include "diff/dpm/dpm.h"

#include "core/batch_stats.h"
#include "core/interrupt.h"
#include "core/seconds.h"
#include "diff/dpm/matching_loss.h"
#include "diff/dpm/photon_path.h"
#include "diff/material_form.h"
#include "diff/pixel_driver.h"
#include "diff/vertex_normals.h"
#include "render/light_medium.h"
#include "render/photon_gather.h"
#include "render/photon_tracing.h"
#include "render/sppm.h"
#include "render/tiles.h"
#include "scene/integrator_settings.h"

#include <tbb/enumerable_thread_specific.h>

#include <atomic>
#include <chrono>
#include <cstdio>

namespace penumbra {

namespace {

// The scene's `sppm` settings (its defaults with the smooth kernel without one).
SPPMSettings photon_mapping_settings(const Scene& scene) {
    if (const SPPMSettings* sppm = sppm_settings(scene)) return *sppm;
    SPPMSettings s;
    s.kernel = PhotonKernel::Smooth;
    return s;
}

// What the estimate cannot follow in the scene's `sppm` settings (docs/dpm.md), for the user.
std::vector<std::string> settings_warnings(const Scene& scene) {
    std::vector<std::string> w;
    const SPPMSettings* sppm = sppm_settings(scene);
    if (!sppm) return w;
    const SPPMSettings& s = *sppm;
    if (s.kernel == PhotonKernel::Constant)
        w.push_back("dpm: the sppm integrator's constant kernel has an edge that is not differentiated; use "
                    "<string name=\"kernel\" value=\"smooth\"/> (paper 003 Eq. 22)");
    if (s.alpha < 1.f)
        w.push_back("dpm: the derivative is the image's at the fixed initial radius, but the sppm integrator's alpha "
                    "< 1 shrinks it (render and fd compute another image); use <float name=\"alpha\" value=\"1\"/>");
    return w;
}

// "differentiable photon mapping (DPM-C, fixed eye rays), 1 of the pixels, 16 paths each".
std::string describe(const DpmOptions& o) {
    char text[160];
    std::snprintf(text, sizeof(text), "differentiable photon mapping (%s), %g of the pixels, %d path%s each",
                  o.variant == DpmVariant::C ? "DPM-C, fixed eye rays"
                                             : "DPM-G, fixed density + vertex merging",
                  o.pixel_fraction, o.paths, o.paths == 1 ? "" : "s");
    return text;
}

void check_options(const Scene& scene, const Parameters& params, const DpmOptions& o) {
    require_film(scene, params);
    if (scene_has_media(scene))
        throw Error("dpm: differentiating photon mapping through participating media is not supported (sppm renders "
                    "them; differentiate with psdr)");
    if (o.spp <= 0 || o.batches <= 0) throw Error("dpm: spp and batches must be positive");
    if (!(o.pixel_fraction > 0.0 && o.pixel_fraction <= 1.0))
        throw Error("dpm: the pixel fraction must be in (0, 1]");
    if (o.paths <= 0) throw Error("dpm: the paths per pixel must be positive");
}

// One differentiated path: its pixel and contribution on the tape (the estimate's scale included), and (DPM-G)
// its screen position.
struct PathSample {
    uint64_t pixel;
    Color3<Var> value;
    Vec2<Var> film;
};

// The passes [first, first + count) of the estimator: calls primal(pixel, L) with each pixel's SPPM estimate
// of each pass, and, on the thread that traced it with its tape current, sample(s) for each differentiated path
// and EPSM (`differentiate` false: the primal only).
template <typename Primal, typename Sample>
void for_each_path(const Scene& scene, const Parameters& params, const DpmOptions& o, uint64_t first,
                   uint64_t count, const std::function<void(float)>& progress, Primal&& primal, Sample&& sample,
                   bool differentiate = true) {
    const Sensor& sensor = *scene.sensor;
    const Film& film = *sensor.film;
    const SPPMSettings s = photon_mapping_settings(scene);
    const float radius = sppm_radius(scene, s);
    const EyeSubpathSettings eye{s.max_depth, s.rr_depth};
    const PhotonTracingSettings light = photon_tracing_settings(s, o.threads);
    // L = Σ_p K f Φ_p / (π r² N) per pass (render/sppm.cpp at a fixed radius).
    const float norm = float(1.0 / (Pi * double(radius) * radius * double(s.photon_count)));
    const std::vector<PhotonPathEpsm> epsms =
        o.variant == DpmVariant::C ? std::vector<PhotonPathEpsm>{PhotonPathEpsm::FixedEyeRay}
                                   : std::vector<PhotonPathEpsm>{PhotonPathEpsm::FixedDensity,
                                                                 PhotonPathEpsm::VertexMerge};
    PhotonMap map;
    for (uint64_t k = 0; k < count; ++k) {
        const uint64_t pass = first + k;
        PhotonTracingStats stats;
        map.build(trace_photons(scene, light, o.seed, pass, stats).surface, radius);
        for_each_tile(film.width, film.height, o.threads, [&](int x0, int y0, int x1, int y1) {
            Sampler sampler(*sensor.sampler, int(std::min<uint64_t>(first + count, kMaxSampleCount)));
            Sampler choice;
            RayCounter rays;
            std::vector<SpecularVertex> chain;
            std::vector<PathVertex> light_path;
            std::vector<std::pair<const Photon*, Color3f>> merged;
            Tape& tape = Tape::current();
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) {
                    check_interrupt();
                    const uint64_t pixel = uint64_t(y) * film.width + x;
                    const auto [vp, ray, pos, emission] =
                        trace_pixel_visible_point(scene, sampler, x, y, o.seed, pass, eye, rays, &chain);
                    if (!vp.valid() || !is_finite(vp.beta)) {
                        if (is_finite(emission)) primal(pixel, emission);
                        continue;
                    }
                    merged.clear();
                    Color3f sum(0.f);
                    float total = 0.f;
                    // vp captured explicitly: clang before 16 cannot capture a structured binding implicitly.
                    for_each_merged_photon(map, vp, radius, s.kernel, s.max_depth,
                                           [&, &vp = vp](const Photon& ph, float kernel, const Color3f& f) {
                                               const Color3f c = f * ph.flux * vp.beta * (kernel * norm);
                                               if (!is_finite(c)) return;
                                               merged.push_back({&ph, c});
                                               sum += c;
                                               total += luminance(c);
                                           });
                    primal(pixel, emission + sum);
                    if (!differentiate) continue;
                    // The pixel differentiates with probability `pixel_fraction`, photons drawn ∝ luminance.
                    choice.start(o.seed ^ 0xd1b54a32d192ed03ULL, pixel, pass);
                    if (!(total > 0.f) || choice.next_1d() >= float(o.pixel_fraction)) continue;
                    for (int n = 0; n < o.paths; ++n) {
                        float u = choice.next_1d() * total;
                        size_t i = 0;
                        while (i + 1 < merged.size() && u >= luminance(merged[i].second))
                            u -= luminance(merged[i++].second);
                        const auto& [ph, c] = merged[i];
                        const float prob = luminance(c) / total;
                        if (!(prob > 0.f)) continue;
                        trace_photon_path(scene, light, o.seed, pass, ph->path, light_path, rays);
                        if (light_path.size() <= ph->depth) continue; // not re-traced identically
                        const PhotonPath path{ray.o, &chain, &vp.si, &light_path, int(ph->depth), radius,
                                              s.kernel};
                        const float scale =
                            1.f / (prob * float(o.pixel_fraction) * float(o.paths) * float(epsms.size()));
                        for (const PhotonPathEpsm epsm : epsms) {
                            tape.clear();
                            PhotonPathValue v;
                            if (!photon_path_value(params, path, epsm, v)) continue;
                            const Color3<Var> value = v.ratio * Color3<Var>(c * scale);
                            if (!std::isfinite(value.x.v + value.y.v + value.z.v)) continue;
                            Vec2<Var> screen(Var(pos.x), Var(pos.y));
                            if (o.variant == DpmVariant::G) {
                                const Vec3<Var> x = to_reference_camera(params, v.first, ray.o);
                                Var jacobian;
                                if (!sensor.film_position(x, Vec3<Var>(-ray.d), screen, jacobian)) continue;
                            }
                            sample(PathSample{pixel, value, screen});
                        }
                    }
                }
            tape.clear();
        });
        if (progress) progress(float(k + 1) / float(count));
    }
}

// A thread's reverse-mode state: its gradient, the sweep's scratch and the seeds (node, adjoint) of one path.
struct ReverseSweep {
    explicit ReverseSweep(size_t dim) : gradient(dim, 0.0) {}
    std::vector<double> gradient;
    std::vector<float> scratch;
    std::vector<std::pair<int32_t, float>> seeds;
    uint64_t dropped = 0; // paths whose adjoint sweep was not finite (the NaN policy)
    void run() { dropped += !Tape::current().backward(seeds, gradient.data(), scratch); }
};

// Σ of the threads' gradients, chained to the parameters (dimension() values).
std::vector<double> total(const Parameters& params, const tbb::enumerable_thread_specific<ReverseSweep>& sweeps) {
    std::vector<double> sum(size_t(params.dimension()), 0.0);
    add_chained_gradient(params, sweeps, sum, &ReverseSweep::gradient);
    return sum;
}

// The threads' count of dropped paths.
uint64_t dropped_paths(const tbb::enumerable_thread_specific<ReverseSweep>& sweeps) {
    uint64_t n = 0;
    for (const ReverseSweep& s : sweeps) n += s.dropped;
    return n;
}

// The SPPM image of the passes [first, first + count), nothing differentiated.
Image primal_image(const Scene& scene, const Parameters& params, const DpmOptions& o, int first, int count) {
    const Film& film = *scene.sensor->film;
    Image image(film.width, film.height);
    const float inv = 1.f / float(count);
    for_each_path(
        scene, params, o, uint64_t(first), uint64_t(count), nullptr,
        [&](uint64_t pixel, const Color3f& l) { image.pixels[pixel] += l * inv; }, [](const PathSample&) {},
        false);
    return image;
}

// Whether the matching loss's gradient is jackknifed: by default, with at least two passes to split.
bool jackknifed(const DpmOptions& o) { return o.matching_jackknife && o.spp >= 2; }

// The matching loss's first run: the primal image (nothing differentiated) and ∂L/∂p, ∂L/∂I of Eq. 25 per
// pixel, from its debiased matching to the target (Xing et al. 2022; at I = T the pull vanishes). Jackknifed,
// the passes are rendered as two halves whose own matchings remove the O(1/passes) noise bias of the gradient
// (diff/dpm/matching_loss.h).
std::pair<Image, MatchingLossResult> matched_primal(const Scene& scene, const Parameters& params,
                                                    const DpmOptions& o, const Image& target) {
    if (!jackknifed(o)) {
        Image primal = primal_image(scene, params, o, 0, o.spp);
        MatchingLossResult loss = image_matching_loss(primal, target, o.matching);
        return {std::move(primal), std::move(loss)};
    }
    const int half = o.spp / 2;
    const SplitImage split{primal_image(scene, params, o, 0, half),
                           primal_image(scene, params, o, half, o.spp - half), half, o.spp - half};
    return {split.whole(), jackknife_matching_loss(split, target, o.matching)};
}

} // namespace

DerivativeImage dpm_derivative(const Scene& scene, const Parameters& params, const DpmOptions& o) {
    const auto start = std::chrono::steady_clock::now();
    check_options(scene, params, o);
    const Film& film = *scene.sensor->film;
    const bool screen = o.variant == DpmVariant::G;
    ImageBatches primal_batches, derivative_batches, x_batches, y_batches;
    std::atomic<uint64_t> dropped{0};
    const std::vector<float> direction = tape_direction(params);
    for (int b = 0; b < o.batches; ++b) {
        Image primal(film.width, film.height), derivative(film.width, film.height);
        Image motion_x(film.width, film.height), motion_y(film.width, film.height);
        const auto progress = o.progress ? std::function<void(float)>([&, b](float f) {
            o.progress((float(b) + f) / float(o.batches));
        })
                                         : std::function<void(float)>();
        tbb::enumerable_thread_specific<std::vector<float>> tangents;
        const float inv = 1.f / float(o.spp);
        // Pixels are disjoint within a pass's tiles: each pixel is written by one thread at a time.
        for_each_path(
            scene, params, o, uint64_t(b) * uint64_t(o.spp), uint64_t(o.spp), progress,
            [&](uint64_t pixel, const Color3f& l) { primal.pixels[pixel] += l * inv; },
            [&](const PathSample& s) {
                std::vector<float>& tangent = tangents.local();
                Tape::current().forward(direction.data(), tangent);
                const Color3f d(tangent_of(s.value.x, tangent), tangent_of(s.value.y, tangent),
                                tangent_of(s.value.z, tangent));
                const Color3f value(s.value.x.v, s.value.y.v, s.value.z.v);
                const Color3f dx = value * tangent_of(s.film.x, tangent), dy = value * tangent_of(s.film.y, tangent);
                if (!is_finite(d) || !is_finite(dx) || !is_finite(dy)) {
                    ++dropped;
                    return;
                }
                derivative.pixels[s.pixel] += d * inv;
                motion_x.pixels[s.pixel] += dx * inv;
                motion_y.pixels[s.pixel] += dy * inv;
            });
        primal_batches.add(primal);
        derivative_batches.add(derivative);
        if (screen) {
            x_batches.add(motion_x);
            y_batches.add(motion_y);
        }
    }
    DerivativeImage out;
    out.derivative = derivative_batches.mean();
    out.stderr_img = derivative_batches.standard_error();
    out.primal = primal_batches.mean();
    out.mean_stderr = derivative_batches.mean_standard_error();
    out.block_stderr = derivative_batches.block_standard_errors();
    out.description = describe(o);
    out.warnings = settings_warnings(scene);
    out.cost.dropped = dropped.load();
    out.seconds = seconds_since(start);
    out.terms.push_back({o.variant == DpmVariant::C ? "photon-mapping" : "contribution", out.derivative,
                         out.stderr_img, out.cost, out.seconds, out.mean_stderr, out.block_stderr});
    if (screen) {
        out.terms.push_back({"screen_x", x_batches.mean(), x_batches.standard_error(), {}, 0.0});
        out.terms.push_back({"screen_y", y_batches.mean(), y_batches.standard_error(), {}, 0.0});
    }
    return out;
}

Gradient dpm_gradient(const Scene& scene, const Parameters& params, const Image& adjoint, const DpmOptions& o) {
    const auto start = std::chrono::steady_clock::now();
    check_options(scene, params, o);
    const Film& film = *scene.sensor->film;
    check_adjoint_size(film, adjoint);
    const size_t dim = size_t(params.tape_dimension());
    tbb::enumerable_thread_specific<ReverseSweep> sweeps([dim] { return ReverseSweep(dim); });
    Gradient out;
    out.primal = Image(film.width, film.height);
    const float inv = 1.f / float(o.spp);
    for_each_path(
        scene, params, o, 0, uint64_t(o.spp), o.progress,
        [&](uint64_t pixel, const Color3f& l) { out.primal.pixels[pixel] += l * inv; },
        [&](const PathSample& s) {
            ReverseSweep& sweep = sweeps.local();
            const Color3f a = adjoint.pixels[s.pixel] * inv;
            sweep.seeds = {{s.value.x.id, a.x}, {s.value.y.id, a.y}, {s.value.z.id, a.z}};
            sweep.run();
        });
    out.values = total(params, sweeps);
    out.cost.dropped = dropped_paths(sweeps);
    out.description = describe(o);
    out.warnings = settings_warnings(scene);
    out.seconds = seconds_since(start);
    return out;
}

Gradient dpm_matching_gradient(const Scene& scene, const Parameters& params, const Image& target,
                               const DpmOptions& o) {
    const auto start = std::chrono::steady_clock::now();
    check_options(scene, params, o);
    const Film& film = *scene.sensor->film;
    if (target.width != film.width || target.height != film.height)
        throw Error("dpm: the target is " + std::to_string(target.width) + "x" +
                    std::to_string(target.height) + ", the film " + std::to_string(film.width) + "x" +
                    std::to_string(film.height));
    const float inv = 1.f / float(o.spp);
    // A pair, not a structured binding: clang before 16 cannot capture one in the lambda below.
    const std::pair<Image, MatchingLossResult> matched = matched_primal(scene, params, o, target);
    const MatchingLossResult& loss = matched.second;

    // Second run: each sampled path estimates its pixel's dI/dθ (its value's scale) and dp/dθ (its screen
    // motion, weighted by its share of the pixel's samples: the pixel fraction, paths, EPSMs and passes).
    const size_t dim = size_t(params.tape_dimension());
    tbb::enumerable_thread_specific<ReverseSweep> sweeps([dim] { return ReverseSweep(dim); });
    const float shares = float(o.pixel_fraction) * float(o.paths) * float(o.variant == DpmVariant::C ? 1 : 2) *
                         float(o.spp);
    DpmOptions independent = o;
    independent.seed = o.seed ^ 0x632be59bd9b4e019ULL;
    for_each_path(
        scene, params, independent, 0, uint64_t(o.spp), o.progress, [](uint64_t, const Color3f&) {},
        [&](const PathSample& s) {
            const Eigen::Index i = Eigen::Index(s.pixel);
            ReverseSweep& sweep = sweeps.local();
            sweep.seeds = {{s.value.x.id, float(loss.d_colour(i, 0)) * inv},
                           {s.value.y.id, float(loss.d_colour(i, 1)) * inv},
                           {s.value.z.id, float(loss.d_colour(i, 2)) * inv},
                           {s.film.x.id, float(loss.d_position(i, 0)) / (float(film.width) * shares)},
                           {s.film.y.id, float(loss.d_position(i, 1)) / (float(film.height) * shares)}};
            sweep.run();
        });
    Gradient out;
    out.values = total(params, sweeps);
    out.primal = matched.first;
    out.description =
        describe(o) +
        (jackknifed(o) ? ", matching loss (jackknife over two halves of the passes)" : ", matching loss");
    out.warnings = settings_warnings(scene);
    out.loss = loss.value;
    out.cost.dropped = dropped_paths(sweeps);
    out.seconds = seconds_since(start);
    return out;
}

} // namespace penumbra
