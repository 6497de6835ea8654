// `bdpt`: bidirectional path tracing (Veach 1997, ch. 10; Mitsuba 0.6's and pbrt-v3's `bdpt`). Each camera
// sample traces a camera subpath and a light subpath and combines every (s, t) connection with multiple
// importance sampling; surfaces and participating media (homogeneous or not) alike.
//
// | parameter     | type    | default | meaning                                                         |
// |---------------|---------|---------|-----------------------------------------------------------------|
// | max_depth     | integer | -1      | longest path in segments (-1 = infinite, 1 = visible emitters)  |
// | rr_depth      | integer | 5       | subpath depth at which Russian roulette starts                  |
// | hide_emitters | boolean | false   | do not show directly visible emitters                           |
// | heuristic     | string  | power   | MIS weights: `power` (exponent 2) or `balance` heuristic        |
// | strategy_s    | integer | -1      | with strategy_t: render only the (s, t) strategy, without MIS   |
// | strategy_t    | integer | -1      | weights (one technique alone: paths of s + t - 1 segments)      |
//
// Light tracing (t = 1) splats into the film like `ptracer`. Light subpaths start in the medium of
// render/light_medium.h (the emitter's nested medium, an area light's exterior, else found from the sensor),
// the rule ptracer follows. Media's `sample_emitters` is ignored: every strategy is always used.
#include "render/bdpt.h"

#include "core/interrupt.h"
#include "core/stratified.h"
#include "render/bdpt_sample.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <mutex>

namespace penumbra {

// Pixels are split into a fixed number of chunks, each with its own light-tracing film, summed in chunk
// order: the image is bit-identical for a given seed whatever the thread count.
std::vector<Layer> BidirectionalPathTracer::render(const Scene& scene, const RenderOptions& options,
                                                   RenderStats& stats) const {
    const Sensor& sensor = *scene.sensor;
    const Film& film = *sensor.film;
    const int width = film.width, height = film.height;
    const int spp = sensor.sampler->effective_spp(options.spp);
    const uint64_t n_pixels = uint64_t(width) * height;
    const BDPTPass pass(scene, settings_, true);

    constexpr int n_chunks = 16;
    std::vector<Image> splats(n_chunks, Image(width, height));
    Image image(width, height);
    std::atomic<uint64_t> rays{0}, done{0}, dropped{0};
    std::mutex progress_mutex;
    const auto start = std::chrono::steady_clock::now();

    const int threads = options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
    tbb::task_arena arena(threads);
    arena.execute([&] {
        tbb::parallel_for(0, n_chunks, [&](int c) {
            Sampler sampler(*sensor.sampler, spp);
            RayCounter counter;
            BDPTSample sample;
            uint64_t local_dropped = 0;
            const uint64_t begin = n_pixels * c / n_chunks, end = n_pixels * (c + 1) / n_chunks;
            for (uint64_t pixel = begin; pixel < end; ++pixel) {
                const int x = int(pixel % width), y = int(pixel / width);
                Color3f sum(0.f);
                for (int s = 0; s < spp; ++s) {
                    check_interrupt(); // per sample: at a large spp, a pixel takes seconds
                    sampler.start(options.seed, pixel, uint64_t(s));
                    const Vec2f u = sampler.next_2d();
                    const Vec2f pos = film.sample_position(
                        x, y, options.stratified ? PixelStratum(s, spp, options.seed, pixel)(u) : u);
                    const Vec2f u_aperture = sampler.next_2d();
                    const auto [ray, weight] = sensor.sample_ray(pos, u_aperture);
                    ++counter.rays;
                    const Color3f L =
                        sample.render(pass, sampler, counter, ray, u_aperture, splats[size_t(c)]);
                    if (is_finite(L))
                        sum += L * weight;
                    else
                        ++local_dropped;
                }
                image.at(x, y) = sum / float(spp);
                const uint64_t finished = ++done;
                if (options.progress && (finished % 256 == 0 || finished == n_pixels)) {
                    std::lock_guard<std::mutex> lock(progress_mutex);
                    options.progress(float(double(finished) / double(n_pixels)));
                }
            }
            rays += counter.rays;
            dropped += local_dropped;
        });
    });

    // Light tracing estimates ∫ f(x - x_j) W_e L with W_e normalized over the image: scale by the image's
    // pixels over the number of light subpaths (one per camera sample), i.e. 1 / spp.
    const float scale = 1.f / float(spp);
    for (const Image& chunk : splats)
        for (size_t i = 0; i < image.pixels.size(); ++i)
            image.pixels[i] += chunk.pixels[i] * scale;

    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    stats.samples = n_pixels * uint64_t(spp);
    stats.rays = rays;
    stats.dropped_samples = dropped;
    return {Layer{"", std::move(image)}};
}

} // namespace penumbra
