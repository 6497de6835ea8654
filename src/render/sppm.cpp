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

SPPMIntegrator::SPPMIntegrator(const Properties& props) {
    photon_count_ = props.get_int("photon_count", 250000);
    initial_radius_ = props.get_float("initial_radius", 0.f);
    alpha_ = props.get_float("alpha", 0.7f);
    max_depth_ = int(props.get_int("max_depth", -1));
    rr_depth_ = int(props.get_int("rr_depth", 5));
    granularity_ = props.get_int("granularity", 0);
    max_passes_ = props.get_int("max_passes", -1);
    const std::string kernel = props.get_string("kernel", "constant");
    if (kernel == "constant")
        kernel_ = PhotonKernel::Constant;
    else if (kernel == "smooth")
        kernel_ = PhotonKernel::Smooth;
    else
        props.raise("kernel", "'kernel' must be 'constant' or 'smooth', got '" + kernel + "'");
    if (photon_count_ <= 0 || photon_count_ > (int64_t(1) << 31))
        props.raise("photon_count",
                    "'photon_count' must be positive (at most 2^31), got " + std::to_string(photon_count_));
    if (!(initial_radius_ >= 0.f) || !std::isfinite(initial_radius_))
        props.raise("initial_radius",
                    "'initial_radius' must be >= 0 (0: automatic), got " + std::to_string(initial_radius_));
    if (!(alpha_ > 0.f && alpha_ <= 1.f))
        props.raise("alpha", "'alpha' must be in (0, 1], got " + std::to_string(alpha_));
    if (max_depth_ < -1) props.raise("max_depth", "'max_depth' must be -1 (infinite) or non-negative");
    if (rr_depth_ <= 0) props.raise("rr_depth", "'rr_depth' must be positive");
    if (granularity_ < 0) props.raise("granularity", "'granularity' must be >= 0 (0: automatic)");
    if (max_passes_ == 0 || max_passes_ < -1)
        props.raise("max_passes", "'max_passes' must be positive or -1 (the sampler's sample count)");
}

std::vector<Layer> SPPMIntegrator::render(const Scene& scene, const RenderOptions& options,
                                          RenderStats& stats) const {
    if (scene_has_media(scene))
        throw Error("sppm: participating media are not supported (render them with volpath or bdpt)");
    const Sensor& sensor = *scene.sensor;
    const Film& film = *sensor.film;
    const int width = film.width, height = film.height;
    const uint64_t passes = options.spp > 0   ? uint64_t(options.spp)
                            : max_passes_ > 0 ? uint64_t(max_passes_)
                                              : uint64_t(sensor.sampler->sample_count);
    const float r0 = initial_radius_ > 0.f
                         ? initial_radius_
                         : 5.f * scene.bounding_sphere().radius / float(std::max(width, height));
    if (!(r0 > 0.f)) throw Error("sppm: the automatic initial radius is 0 (an empty scene?)");

    std::vector<SPPMPixel> pixels(size_t(width) * height);
    for (SPPMPixel& px : pixels)
        px.radius = r0;
    std::vector<VisiblePoint> points(pixels.size());
    const EyeSubpathSettings eye{max_depth_, rr_depth_};
    PhotonTracingSettings light;
    light.paths = uint64_t(photon_count_);
    light.max_depth = max_depth_;
    light.rr_depth = rr_depth_;
    light.granularity = uint64_t(granularity_);
    light.threads = options.threads;
    std::atomic<uint64_t> rays{0}, dropped{0};
    PhotonMap map;
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
                    sampler.start(options.seed, pixel, pass);
                    const Vec2f pos = film.sample_position(x, y, sampler.next_2d());
                    const auto [ray, weight] = sensor.sample_ray(pos, sampler.next_2d());
                    Color3f emission(0.f);
                    VisiblePoint vp =
                        trace_visible_point(scene, sampler, ray, weight, eye, emission, counter);
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
        std::vector<Photon> photons = trace_photons(scene, light, options.seed, pass, photon_stats);
        rays += photon_stats.rays;
        float cell = 0.f;
        for (size_t i = 0; i < pixels.size(); ++i)
            if (points[i].valid()) cell = std::max(cell, pixels[i].radius);
        if (cell > 0.f) {
            map.build(std::move(photons), cell);
            // Progressive radius reduction and flux correction (progressive photon mapping,
            // Hachisuka et al. 2008, per pixel as in SPPM):
            // N' = N + αM, R' = R √(N' / (N + M)), τ' = (τ + Φ) R'² / R².
            for_each_tile(width, height, options.threads, [&](int x0, int y0, int x1, int y1) {
                for (int y = y0; y < y1; ++y)
                    for (int x = x0; x < x1; ++x) {
                        const size_t pixel = size_t(y) * width + x;
                        if (!points[pixel].valid()) continue;
                        SPPMPixel& px = pixels[pixel];
                        const PhotonGather g =
                            gather_photons(map, points[pixel], px.radius, kernel_, max_depth_);
                        if (!(g.count > 0.f)) continue;
                        const float n_new = px.count + alpha_ * g.count;
                        const float ratio = n_new / (px.count + g.count);
                        px.tau = (px.tau + g.flux) * ratio;
                        px.radius *= std::sqrt(ratio);
                        px.count = n_new;
                    }
            });
        }
        if (options.progress) options.progress(float(double(pass + 1) / double(passes)));
    }

    // L = L_e / passes + τ / (π R² N_emitted), N_emitted = passes × photon_count.
    Image image(width, height);
    const double emitted = double(passes) * double(photon_count_);
    for (size_t i = 0; i < pixels.size(); ++i) {
        const SPPMPixel& px = pixels[i];
        image.pixels[i] = px.emission / float(passes) +
                          px.tau * float(1.0 / (Pi * double(px.radius) * px.radius * emitted));
    }
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    stats.samples = uint64_t(pixels.size()) * passes;
    stats.rays = rays;
    stats.dropped_samples = dropped;
    return {Layer{"", std::move(image)}};
}

} // namespace penumbra
