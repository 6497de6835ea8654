// What the boundary estimators share: a boundary sample is one or more film positions s with detached weights
// (the discontinuity's jump times the measure conversions, over the sampling density) and the normal velocity
// of the discontinuity as a tape expression. The drivers run the samples in 16 fixed chunks (results do not
// depend on the thread count), splat weight × dv/dθ through the pixel filter in forward mode, and propagate the
// filter-weighted adjoint back to the parameters in reverse mode.
#pragma once
#include "diff/parameters.h"
#include "render/film_footprint.h"
#include "render/path_tracer.h"

#include <array>
#include <utility>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace penumbra {

struct BoundaryOptions {
    int samples_per_pixel = 4; // boundary samples = this × the number of pixels
    uint64_t seed = 0;
    int threads = 0;
    PathSettings path;
};

struct BoundarySample {
    Var velocity; // value ~0; its derivative is the discontinuity's normal velocity
    // Where the discontinuity's contribution lands: film positions (pixels) with detached factors; several for a
    // detector subpath connected to the camera at several vertices, none for a failed sample.
    static constexpr int MaxSplats = 8;
    std::array<std::pair<Vec2f, Color3f>, MaxSplats> splats;
    int n_splats = 0;

    void add_splat(const Vec2f& s, const Color3f& weight) {
        if (n_splats < MaxSplats) splats[n_splats++] = {s, weight};
    }
    bool usable() const {
        if (n_splats == 0 || velocity.id < 0) return false;
        for (int k = 0; k < n_splats; ++k)
            if (!is_finite(splats[k].second)) return false;
        return true;
    }
};

// A boundary term of the differential path integral: an estimator with its own sample budget.
class BoundaryTerm {
public:
    virtual ~BoundaryTerm() = default;
    // Forward mode: the term's contribution to dI/dθ.
    virtual Image derivative(const Parameters& params, const BoundaryOptions& options) const = 0;
    // Reverse mode: adds Σ_pixels adjoint · (the term) to `gradient`.
    virtual void gradient(const Parameters& params, const Image& adjoint, const BoundaryOptions& options,
                          std::vector<double>& gradient) const = 0;
};

namespace detail {

template <typename Body> void for_each_sample(const Film& film, const BoundaryOptions& options, uint64_t salt, const Body& body) {
    const uint64_t n = uint64_t(film.width) * film.height * uint64_t(options.samples_per_pixel);
    constexpr int chunks = 16;
    tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency());
    arena.execute([&] {
        tbb::parallel_for(0, chunks, [&](int c) {
            Sampler sampler;
            for (uint64_t i = n * c / chunks; i < n * (c + 1) / chunks; ++i) {
                sampler.start(options.seed ^ salt, i, 0);
                body(c, sampler);
            }
        });
    });
}

} // namespace detail

// Forward mode: Σ_samples P_j(s) weight dv/dθ / N for every pixel j. `sample(Sampler&, RayCounter&)` draws
// one BoundarySample (recording its velocity on the thread's tape).
template <typename SampleFn>
Image boundary_derivative(const Scene& scene, const Parameters& params, const BoundaryOptions& options, uint64_t salt,
                          const SampleFn& sample) {
    const Film& film = *scene.sensor->film;
    const double n = double(film.width) * film.height * options.samples_per_pixel;
    std::vector<Image> chunks(16, Image(film.width, film.height));
    detail::for_each_sample(film, options, salt, [&](int c, Sampler& sampler) {
        thread_local std::vector<float> tangent;
        Tape& tape = Tape::current();
        tape.clear();
        RayCounter rays;
        const BoundarySample b = sample(sampler, rays);
        if (b.usable()) {
            tape.forward(params.direction().data(), tangent);
            const float dv = float(double(tangent[b.velocity.id]) / n);
            for (int k = 0; k < b.n_splats; ++k) {
                const Color3f value = b.splats[k].second * dv;
                for_each_pixel_in_footprint(film, b.splats[k].first, [&](int x, int y, float w) { chunks[c].at(x, y) += value * w; });
            }
        }
        tape.clear();
    });
    Image result(film.width, film.height);
    for (const Image& chunk : chunks)
        for (size_t i = 0; i < result.pixels.size(); ++i) result.pixels[i] += chunk.pixels[i];
    return result;
}

// Reverse mode: adds Σ_samples (Σ_j adjoint_j P_j(s)) · weight · dv/dθ / N to `gradient`.
template <typename SampleFn>
void boundary_gradient(const Scene& scene, const Image& adjoint, const BoundaryOptions& options, uint64_t salt,
                       const SampleFn& sample, std::vector<double>& gradient) {
    const Film& film = *scene.sensor->film;
    const double n = double(film.width) * film.height * options.samples_per_pixel;
    const size_t dim = gradient.size();
    tbb::enumerable_thread_specific<std::vector<double>> local([dim] { return std::vector<double>(dim, 0.0); });
    detail::for_each_sample(film, options, salt, [&](int, Sampler& sampler) {
        thread_local std::vector<float> scratch;
        Tape& tape = Tape::current();
        tape.clear();
        RayCounter rays;
        const BoundarySample b = sample(sampler, rays);
        if (b.usable()) {
            double seed = 0;
            for (int k = 0; k < b.n_splats; ++k)
                for_each_pixel_in_footprint(film, b.splats[k].first,
                                            [&](int x, int y, float w) { seed += w * dot(adjoint.at(x, y), b.splats[k].second); });
            tape.backward({{b.velocity.id, float(seed / n)}}, local.local().data(), scratch);
        }
        tape.clear();
    });
    for (const auto& g : local)
        for (size_t k = 0; k < dim; ++k) gradient[k] += g[k];
}

} // namespace penumbra
