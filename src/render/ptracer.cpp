// `ptracer`: light tracing. Paths start on emitters and every vertex is connected to the camera
// (Mitsuba 3's `ptracer`).
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

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <mutex>

namespace penumbra {

ParticleTracer::ParticleTracer(const Properties& props) {
    max_depth_ = int(props.get_int("max_depth", -1));
    rr_depth_ = int(props.get_int("rr_depth", 5));
    hide_emitters_ = props.get_bool("hide_emitters", false);
    if (max_depth_ < -1) props.raise("max_depth", "must be -1 (infinite) or non-negative");
    if (rr_depth_ <= 0) props.raise("rr_depth", "must be positive");
}

void ParticleTracer::trace(const Scene& scene, Sampler& sampler, Image& image, RayCounter& rays) const {
    const BSDFContext ctx{TransportMode::Importance};
    const Sensor& sensor = *scene.sensor;
    const Film& film = *sensor.film;
    auto splat = [&](const Vec2f& pos, const Color3f& value) {
        for_each_pixel_in_footprint(film, pos, [&](int x, int y, float w) { image.at(x, y) += value * w; });
    };
    const unsigned max_depth = unsigned(max_depth_);
    if (max_depth_ == 0 || scene.emitters.empty()) return;

    float u_sel = sampler.next_1d(), pdf_sel = 0.f;
    const Emitter* emitter = scene.sample_emitter(u_sel, pdf_sel);

    // Depth 1: the emitter seen directly by the camera, I = ∫ W_e L_e |cos θ_x| / d² dA (area emitters only:
    // point and directional emitters occupy no area on the film).
    const Vec2f u_pos = sampler.next_2d(), u_sensor = sampler.next_2d();
    if (!hide_emitters_ && emitter->shape()) {
        const PositionSample3f ps = emitter->shape()->sample_position(u_pos);
        SurfaceInteraction3f si;
        si.p = ps.p;
        si.n = ps.n;
        si.sh_frame = Frame3f(ps.n);
        si.uv = ps.uv;
        si.shape = emitter->shape();
        const auto [sds, sw] = sensor.sample_direction(si, u_sensor);
        ++rays.rays;
        if (!is_black(sw) && !scene.occluded(si.spawn_ray_to(sds.p))) {
            si.wi = si.to_local(sds.d); // toward the camera
            const Color3f Le = emitter->eval(si);
            const float cos_x = std::abs(dot(ps.n, sds.d));
            splat(sds.uv, Le * sw * (cos_x / (ps.pdf * pdf_sel)));
        }
    }

    const Vec2f u_dir = sampler.next_2d();
    auto [ray, weight] = emitter->sample_ray(u_pos, u_dir);
    Color3f throughput = weight / pdf_sel;
    ++rays.rays;
    for (unsigned depth = 1;; ++depth) {
        if (is_black(throughput)) break;
        const SurfaceInteraction3f si = scene.intersect(ray);
        if (!si.is_valid()) break;
        const BSDF* bsdf = si.bsdf();
        if (!bsdf) break;

        // Connect to the camera: the full path has depth + 1 segments.
        const Vec2f u_connect = sampler.next_2d();
        if (depth + 1 <= max_depth && bsdf->has(BSDFSmooth)) {
            const auto [sds, sw] = sensor.sample_direction(si, u_connect);
            ++rays.rays;
            if (!is_black(sw) && !scene.occluded(si.spawn_ray_to(sds.p))) {
                const Vec3f w_next = sds.d; // from si toward the camera
                const Color3f f = bsdf->eval(ctx, si, si.to_local(w_next)) * adjoint_shading_correction(si, w_next);
                splat(sds.uv, throughput * f * sw);
            }
        }
        if (depth + 1 >= max_depth) break;

        const float u1 = sampler.next_1d();
        const auto [bs, bsdf_weight] = bsdf->sample(ctx, si, u1, sampler.next_2d());
        if (is_black(bsdf_weight)) break;
        const Vec3f d = si.to_world(bs.wo);
        throughput *= bsdf_weight * adjoint_shading_correction(si, d);
        ray = si.spawn_ray(d);
        ++rays.rays;
        if (depth >= unsigned(rr_depth_)) {
            const float q = std::min(max_component(throughput), 0.95f);
            if (sampler.next_1d() >= q) break;
            throughput /= q;
        }
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
                trace(scene, sampler, chunks[c], counter);
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
