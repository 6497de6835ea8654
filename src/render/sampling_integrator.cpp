#include "core/interrupt.h"
#include "core/stratified.h"
#include "render/integrator.h"
#include "render/tiles.h"

#include <chrono>

namespace penumbra {

// Every pixel is estimated from the scene sampler's numbers, a pure function of (seed, pixel, sample index,
// dimension), and written by exactly one task, so the image does not depend on scheduling or thread count.
std::vector<Layer> SamplingIntegrator::render(const Scene& scene, const RenderOptions& options,
                                              RenderStats& stats) const {
    const Sensor& sensor = *scene.sensor;
    const Film& film = *sensor.film;
    const int width = film.width, height = film.height;
    const int spp = sensor.sampler->effective_spp(options.spp);
    const std::vector<std::string> names = layer_names(), channels = layer_channels();
    const size_t n_layers = names.size();
    std::vector<Layer> layers;
    for (size_t l = 0; l < n_layers; ++l)
        layers.push_back({names[l], Image(width, height), channels[l]});
    // The film's alpha (Mitsuba: whether the camera ray hits a surface), filtered like the other layers.
    const bool alpha = film.has_alpha();
    if (alpha) layers.push_back({"", Image(width, height), "A"});
    std::atomic<uint64_t> rays{0}, dropped{0};
    const auto start = std::chrono::steady_clock::now();

    for_each_tile(width, height, options.threads, [&](int x0, int y0, int x1, int y1) {
        Sampler sampler(*sensor.sampler, spp);
        RayCounter counter;
        std::vector<Color3f> value(n_layers), sum(layers.size());
        uint64_t local_dropped = 0;
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                const uint64_t pixel = uint64_t(y) * width + x;
                std::fill(sum.begin(), sum.end(), Color3f(0.f));
                for (int s = 0; s < spp; ++s) {
                    check_interrupt(); // per sample: at a large spp, a pixel takes seconds
                    sampler.start(options.seed, pixel, uint64_t(s));
                    // Filter importance sampling: the pixel estimate is ∫ f(x - x_j) L(x) dx with f normalized.
                    const Vec2f u = sampler.next_2d();
                    const Vec2f pos = film.sample_position(
                        x, y, options.stratified ? PixelStratum(s, spp, options.seed, pixel)(u) : u);
                    const auto [ray, weight] = sensor.sample_ray(pos, sampler.next_2d());
                    ++counter.rays;
                    sample(scene, sampler, ray, value.data(), counter);
                    bool finite = true;
                    for (auto& v : value) finite = finite && is_finite(v);
                    if (!finite) {
                        ++local_dropped;
                        continue;
                    }
                    for (size_t l = 0; l < n_layers; ++l) sum[l] += value[l] * weight;
                    if (alpha) {
                        ++counter.rays;
                        if (scene.intersect(ray).is_valid()) sum[n_layers] += Color3f(1.f);
                    }
                }
                for (size_t l = 0; l < layers.size(); ++l)
                    layers[l].image.at(x, y) = sum[l] / float(spp);
            }
        rays += counter.rays;
        dropped += local_dropped;
    }, options.progress);

    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    stats.samples = uint64_t(width) * height * spp;
    stats.rays = rays;
    stats.dropped_samples = dropped;
    return layers;
}

} // namespace penumbra
