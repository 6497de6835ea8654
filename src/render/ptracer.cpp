// `ptracer`: light tracing. Paths start on emitters and every vertex is connected to the camera
// (Mitsuba 3's `ptracer`), through participating media: light paths scatter in media (free-flight and phase
// sampling, render/medium_sampling.h), start in the emitter's medium (render/light_medium.h states the rule),
// and every connection to the camera carries the transmittance of its segment through media and null
// boundaries (segment_transmittance), with the phase function at medium vertices. As in volpath, crossing a
// null lobe is not a bounce for max_depth (Mitsuba's ptracer, which has no media, counts it).
//
// | parameter      | type    | default | meaning                                                    |
// |----------------|---------|---------|------------------------------------------------------------|
// | max_depth      | integer | -1      | longest path depth (-1 = infinite, 1 = visible emitters)    |
// | rr_depth       | integer | 5       | depth at which Russian roulette starts                     |
// | hide_emitters  | boolean | false   | do not show directly visible emitters                      |
#include "render/ptracer.h"

#include "core/interrupt.h"
#include "render/adjoint_shading.h"
#include "render/film_footprint.h"
#include "render/light_medium.h"
#include "render/medium_sampling.h"
#include "render/volume_visibility.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <mutex>

namespace penumbra {

namespace {

// Russian roulette on the light path (survival probability min(max(throughput), 0.95)).
bool survives_roulette(Color3f& throughput, Sampler& sampler) {
    const float q = std::min(max_component(throughput), 0.95f);
    if (sampler.next_1d() >= q) return false;
    throughput /= q;
    return true;
}

} // namespace

void ParticleTracer::trace(const Scene& scene, bool media, Sampler& sampler, Image& image, RayCounter& rays) const {
    const BSDFContext ctx{TransportMode::Importance};
    const Sensor& sensor = *scene.sensor;
    const Film& film = *sensor.film;
    auto splat = [&](const Vec2f& pos, const Color3f& value) {
        for_each_pixel_in_footprint(film, pos, [&](int x, int y, float w) { image.at(x, y) += value * w; });
    };
    // Connects vertex `ref` (on `shape`, or in `medium` when shape is null) to the sensor and splats
    // throughput · f · W_e / p · Tr, with f(w) the BSDF or phase function toward the camera; the connection
    // starts in the medium on the camera's side of the surface.
    auto connect = [&](const Interaction3f& ref, const Shape* shape, const Medium* medium,
                       const Color3f& throughput, auto&& f) {
        const auto [sds, sw] = sensor.sample_direction(ref, sampler.next_2d());
        if (is_black(sw)) return;
        const Color3f value = throughput * f(sds.d) * sw;
        if (is_black(value)) return;
        if (shape) medium = target_medium(*shape, ref.n, sds.d, medium);
        const Color3f tr = segment_transmittance(scene, ref.spawn_ray_to(sds.p), medium, sampler, rays);
        if (!is_black(tr)) splat(sds.uv, value * tr);
    };
    const unsigned max_depth = unsigned(settings_.max_depth);
    if (settings_.max_depth == 0 || scene.emitters.empty()) return;

    float u_sel = sampler.next_1d(), pdf_sel = 0.f;
    const Emitter* emitter = scene.sample_emitter(u_sel, pdf_sel);

    // Depth 1: the emitter seen directly by the camera, I = ∫ W_e L_e Tr |cos θ_x| / d² dA (area emitters only:
    // point and directional emitters occupy no area on the film).
    const Vec2f u_pos = sampler.next_2d();
    if (!settings_.hide_emitters && emitter->shape()) {
        const PositionSample3f ps = emitter->shape()->sample_position(u_pos);
        SurfaceInteraction3f si;
        si.p = ps.p;
        si.n = ps.n;
        si.sh_frame = Frame3f(ps.n);
        si.uv = ps.uv;
        si.shape = emitter->shape();
        const Medium* medium = media ? emitter_medium(scene, *emitter, si.spawn_ray(ps.n).o, rays) : nullptr;
        connect(si, si.shape, medium, Color3f(1.f / (ps.pdf * pdf_sel)), [&](const Vec3f& to_camera) {
            si.wi = si.to_local(to_camera);
            return emitter->eval(si) * std::abs(dot(ps.n, to_camera));
        });
    } else {
        sampler.next_2d();
    }

    const Vec2f u_dir = sampler.next_2d();
    auto [ray, weight] = emitter->sample_ray(u_pos, u_dir);
    Color3f throughput = weight / pdf_sel;
    const Medium* medium = media ? emitter_medium(scene, *emitter, ray.o, rays) : nullptr;
    ++rays.rays;
    // depth: the segments of the light path up to the current vertex, null crossings excluded (as volpath);
    // connecting a vertex to the camera makes a path of depth + 1 segments.
    for (unsigned depth = 1;;) {
        if (is_black(throughput)) break;
        const SurfaceInteraction3f si = scene.intersect(ray);

        if (medium) {
            const FreeFlightSample ff =
                sample_free_flight(*medium, ray.o, ray.d, si.is_valid() ? si.t : Infinity, sampler);
            throughput *= ff.weight;
            if (is_black(throughput)) break;
            if (ff.event == FreeFlightSample::Event::Scattered) {
                // A medium vertex: connect with the phase function (symmetric: the same in both directions).
                const PhaseFunction& phase = *medium->phase;
                const Vec3f wi = -ray.d;
                Interaction3f mi;
                mi.p = ff.p;
                mi.t = 0.f;
                if (depth + 1 <= max_depth)
                    connect(mi, nullptr, medium, throughput,
                            [&](const Vec3f& wo) { return Color3f(phase.eval<float>(wi, wo)); });
                if (depth + 1 >= max_depth) break;
                const auto [wo, pdf] = phase.sample(wi, sampler.next_2d());
                if (!(pdf > 0.f)) break;
                ray = Ray(ff.p, wo);
                ++rays.rays;
                if (depth >= unsigned(settings_.rr_depth) && !survives_roulette(throughput, sampler)) break;
                ++depth;
                continue;
            }
        }
        if (!si.is_valid()) break;
        const BSDF* bsdf = si.bsdf();
        if (!bsdf) break;

        // Connect to the camera through the medium on the camera's side of the surface.
        if (depth + 1 <= max_depth && bsdf->has(BSDFSmooth)) {
            connect(si, si.shape, medium, throughput, [&](const Vec3f& w_next) {
                return bsdf->eval(ctx, si, si.to_local(w_next)) * adjoint_shading_correction(si, w_next);
            });
        } else {
            sampler.next_2d();
        }

        const float u1 = sampler.next_1d();
        const auto [bs, bsdf_weight] = bsdf->sample(ctx, si, u1, sampler.next_2d());
        if (is_black(bsdf_weight)) break;
        const bool null = bs.sampled_type == BSDFNull;
        if (!null && depth + 1 >= max_depth) break;
        const Vec3f d = si.to_world(bs.wo);
        throughput *= null ? bsdf_weight : bsdf_weight * adjoint_shading_correction(si, d);
        medium = target_medium(*si.shape, si.n, d, medium);
        ray = si.spawn_ray(d);
        ++rays.rays;
        if (null) continue;
        if (depth >= unsigned(settings_.rr_depth) && !survives_roulette(throughput, sampler)) break;
        ++depth;
    }
}

// Light paths are split into a fixed number of chunks, each with its own film traced in a fixed order and
// summed in chunk order: the image is bit-identical for a given seed whatever the thread count.
std::vector<Layer> ParticleTracer::render(const Scene& scene, const RenderOptions& options, RenderStats& stats) const {
    const Film& film = *scene.sensor->film;
    const int spp = scene.sensor->sampler->effective_spp(options.spp);
    const uint64_t n_paths = uint64_t(film.width) * film.height * spp;
    constexpr int n_chunks = 16;
    std::vector<Image> chunks(n_chunks, Image(film.width, film.height));
    std::atomic<uint64_t> rays{0}, done{0};
    std::mutex progress_mutex;
    const auto start = std::chrono::steady_clock::now();
    constexpr uint64_t batch = 4096;

    const bool media = scene_has_media(scene);
    const int threads = options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
    tbb::task_arena arena(threads);
    arena.execute([&] {
        tbb::parallel_for(0, n_chunks, [&](int c) {
            Sampler sampler;
            RayCounter counter;
            const uint64_t begin = n_paths * c / n_chunks, end = n_paths * (c + 1) / n_chunks;
            for (uint64_t i = begin; i < end; ++i) {
                if ((i & 1023) == 0) check_interrupt();
                sampler.start(options.seed ^ 0x9e3779b97f4a7c15ULL, i, 0);
                trace(scene, media, sampler, chunks[c], counter);
                if ((i - begin + 1) % batch == 0 || i + 1 == end) {
                    const uint64_t total = done += ((i - begin) % batch) + 1;
                    if (options.progress) {
                        std::lock_guard<std::mutex> lock(progress_mutex);
                        options.progress(float(double(total) / double(n_paths)));
                    }
                }
            }
            rays += counter.rays;
        });
    });

    // Each pixel value is ∫ f(x - x_j) W_e L dω with W_e normalized over the film: scale by the film area in pixels
    // over the number of light paths (= 1/spp).
    Image image(film.width, film.height);
    const float scale = float(double(film.width) * film.height / double(n_paths));
    for (const Image& chunk : chunks)
        for (size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] += chunk.pixels[i];
    for (auto& p : image.pixels) p *= scale;

    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    stats.samples = n_paths;
    stats.rays = rays;
    return {Layer{"", std::move(image)}};
}

} // namespace penumbra
