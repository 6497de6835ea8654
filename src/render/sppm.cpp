// `sppm`: stochastic progressive photon mapping (Hachisuka & Jensen 2009; Mitsuba 0.6's `sppm`). Every pass
// traces one eye subpath per pixel to its visible point (render/visible_point.h), traces photon_count light
// subpaths (render/photon_tracing.h), and merges each visible point with the photons within its pixel's
// radius (render/photon_gather.h), then shrinks the radius and rescales the pixel's flux. All light
// but the emission eye subpaths reach through specular chains comes from photons, direct light included
// (Mitsuba 0.6's choice). Memory does not grow with the passes, and the image is bit-identical for a seed
// whatever the thread count.
//
// | parameter      | type    | default  | meaning                                                         |
// |----------------|---------|----------|-----------------------------------------------------------------|
// | photon_count   | integer | 250000   | light subpaths traced per pass                                  |
// | initial_radius | float   | 0        | initial merging radius (0: 5 × scene radius / max(width, height)) |
// | alpha          | float   | 0.7      | radius reduction α ∈ (0, 1]: the share of new photons kept      |
// | max_depth      | integer | -1       | longest path in segments (-1 = infinite, 1 = visible emitters)  |
// | rr_depth       | integer | 5        | depth at which Russian roulette starts (eye and light subpaths) |
// | granularity    | integer | 0        | light subpaths per work unit (0: automatic); the image is equal |
// | max_passes     | integer | -1       | passes (-1: the sampler's sample_count; `--spp` overrides both) |
// | kernel         | string  | constant | density-estimation kernel: `constant` or `smooth` (paper 003 Eq.
// 22) |
#include "render/sppm.h"

#include "core/interrupt.h"
#include "render/light_medium.h"
#include "render/photon_gather.h"
#include "render/photon_tracing.h"
#include "render/tiles.h"
#include "render/visible_point.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>

namespace penumbra {

float sppm_radius(const Scene& scene, const SPPMSettings& settings) {
    if (settings.initial_radius > 0.f) return settings.initial_radius;
    const Film& film = *scene.sensor->film;
    const float r = 5.f * scene.bounding_sphere().radius / float(std::max(film.width, film.height));
    if (!(r > 0.f)) throw Error("sppm: the automatic initial radius is 0 (an empty scene?)");
    return r;
}

PhotonTracingSettings photon_tracing_settings(const SPPMSettings& settings, int threads) {
    PhotonTracingSettings light;
    light.paths = uint64_t(settings.photon_count);
    light.max_depth = settings.max_depth;
    light.rr_depth = settings.rr_depth;
    light.granularity = uint64_t(settings.granularity);
    light.threads = threads;
    return light;
}

std::vector<Layer> SPPMIntegrator::render(const Scene& scene, const RenderOptions& options,
                                          RenderStats& stats) const {
    const Sensor& sensor = *scene.sensor;
    const Film& film = *sensor.film;
    const int width = film.width, height = film.height;
    const uint64_t passes = options.spp > 0   ? uint64_t(options.spp)
                            : s_.max_passes > 0 ? uint64_t(s_.max_passes)
                                              : uint64_t(sensor.sampler->sample_count);
    const float r0 = sppm_radius(scene, s_);

    std::vector<SPPMPixel> pixels(size_t(width) * height);
    for (SPPMPixel& px : pixels)
        px.radius = px.volume_radius = r0;
    std::vector<VisiblePoint> points(pixels.size());
    const EyeSubpathSettings eye{s_.max_depth, s_.rr_depth};
    const PhotonTracingSettings light = photon_tracing_settings(s_, options.threads);
    std::atomic<uint64_t> rays{0}, dropped{0};
    PhotonMap map, volume_map;
    const auto start = std::chrono::steady_clock::now();

    for (uint64_t pass = 0; pass < passes; ++pass) {
        // Eye pass: one visible point per pixel, from the camera sampler's sample `pass` of the pixel.
        for_each_tile(width, height, options.threads, [&](int x0, int y0, int x1, int y1) {
            Sampler sampler(*sensor.sampler, int(std::min<uint64_t>(passes, kMaxSampleCount)));
            RayCounter counter;
            uint64_t local_dropped = 0;
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) {
                    const size_t pixel = size_t(y) * width + x;
                    auto [vp, ray, pos, emission] =
                        trace_pixel_visible_point(scene, sampler, x, y, options.seed, pass, eye, counter);
                    if (!is_finite(emission) || !is_finite(vp.beta)) {
                        ++local_dropped;
                        vp = {};
                        emission = Color3f(0.f);
                    }
                    pixels[pixel].emission += emission;
                    points[pixel] = vp;
                }
            rays += counter.rays;
            dropped += local_dropped;
        });

        // Photon pass, then the grid with cells as large as the largest radius of a visible point.
        PhotonTracingStats photon_stats;
        PhotonSet photons = trace_photons(scene, light, options.seed, pass, photon_stats);
        rays += photon_stats.rays;
        float cell = 0.f, volume_cell = 0.f;
        for (size_t i = 0; i < pixels.size(); ++i) {
            if (points[i].in_medium()) volume_cell = std::max(volume_cell, pixels[i].volume_radius);
            else if (points[i].valid()) cell = std::max(cell, pixels[i].radius);
        }
        if (cell > 0.f) map.build(std::move(photons.surface), cell);
        if (volume_cell > 0.f) volume_map.build(std::move(photons.volume), volume_cell);
        // Progressive radius reduction and flux correction (progressive photon mapping, Hachisuka et al.
        // 2008, per pixel as in SPPM): N' = N + αM, R' = R (N' / (N + M))^(1/d), τ' = (τ + Φ) (R' / R)^d,
        // d = 2 on surfaces, 3 in media.
        if (cell > 0.f || volume_cell > 0.f)
            for_each_tile(width, height, options.threads, [&](int x0, int y0, int x1, int y1) {
                for (int y = y0; y < y1; ++y)
                    for (int x = x0; x < x1; ++x) {
                        const size_t pixel = size_t(y) * width + x;
                        const VisiblePoint& vp = points[pixel];
                        if (!vp.valid()) continue;
                        SPPMPixel& px = pixels[pixel];
                        const bool volume = vp.in_medium();
                        float& radius = volume ? px.volume_radius : px.radius;
                        float& count = volume ? px.volume_count : px.count;
                        Color3f& tau = volume ? px.volume_tau : px.tau;
                        const PhotonGather g =
                            volume ? gather_volume_photons(volume_map, vp, radius, s_.kernel, s_.max_depth)
                                   : gather_photons(map, vp, radius, s_.kernel, s_.max_depth);
                        if (!(g.count > 0.f)) continue;
                        const float n_new = count + s_.alpha * g.count;
                        const float ratio = n_new / (count + g.count);
                        tau = (tau + g.flux) * ratio;
                        radius *= volume ? std::cbrt(ratio) : std::sqrt(ratio);
                        count = n_new;
                    }
            });
        if (options.progress) options.progress(float(double(pass + 1) / double(passes)));
    }

    // L = L_e / passes + τ / (π R² N_emitted) + τ_v / (4/3 π R_v³ N_emitted), N_emitted = passes × photon_count.
    Image image(width, height);
    const double emitted = double(passes) * double(s_.photon_count);
    for (size_t i = 0; i < pixels.size(); ++i) {
        const SPPMPixel& px = pixels[i];
        const double rv3 = double(px.volume_radius) * px.volume_radius * px.volume_radius;
        image.pixels[i] = px.emission / float(passes) +
                          px.tau * float(1.0 / (Pi * double(px.radius) * px.radius * emitted)) +
                          px.volume_tau * float(1.0 / (4.0 / 3.0 * Pi * rv3 * emitted));
    }
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    stats.samples = uint64_t(pixels.size()) * passes;
    stats.rays = rays;
    stats.dropped_samples = dropped;
    return {Layer{"", std::move(image)}};
}

} // namespace penumbra
