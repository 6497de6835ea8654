// What the boundary estimators share: a boundary sample is one or more film positions s, each with a detached
// weight (the discontinuity's jump times the measure conversions, over the sampling density) and the normal
// velocity of the discontinuity as a tape expression (in the parameterization of the vertex the splat belongs
// to: a receiver seen directly by an image-space camera moves differently from one in material form). The drivers
// run the samples in 16 fixed chunks (results do not depend on the thread count), splat weight × dv/dθ through
// the pixel filter in forward mode, and propagate the filter-weighted adjoint back to the parameters in reverse
// mode.
#pragma once
#include "core/interrupt.h"
#include "diff/first_vertex.h"
#include "diff/parameters.h"
#include "diff/sample_cost.h"
#include "diff/vertex_normals.h"
#include "render/film_footprint.h"
#include "render/path_tracer.h"

#include <algorithm>
#include <array>
#include <cmath>
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
    FirstVertex first_vertex = FirstVertex::Auto; // must match the interior term's (diff/first_vertex.h)
    bool guiding = true;                          // terms that can guide their sampling by a pilot do
    bool volume_endpoints = true;                 // boundary segments may end at medium vertices (shadow sheets)
    SampleCost* cost = nullptr;                   // if set, the samples' cost is added to it
};

struct BoundarySample {
    // Where the discontinuity's contribution lands: film positions (pixels) with detached factors; several for a
    // detector subpath connected to the camera at several vertices, none for a failed sample.
    struct Splat {
        Vec2f s;
        Color3f weight;
        Var velocity; // value ~0; its derivative is the discontinuity's normal velocity
    };
    static constexpr int MaxSplats = 8;
    std::array<Splat, MaxSplats> splats;
    int n_splats = 0;

    void add_splat(const Vec2f& s, const Color3f& weight, const Var& velocity) {
        if (n_splats < MaxSplats && velocity.id >= 0) splats[n_splats++] = {s, weight, velocity};
    }
    bool usable() const {
        if (n_splats == 0) return false;
        for (int k = 0; k < n_splats; ++k)
            if (!is_finite(splats[k].weight)) return false;
        return true;
    }
};

// Sample i of the n samples of a boundary estimator. Its first random number is stratified over the n samples
// (systematic sampling of the edges' total length, instead of independent positions): each edge, and each
// pixel an edge crosses, gets a nearly deterministic share of the samples.
struct BoundarySampleIndex {
    uint64_t i, n;
    float stratified(Sampler& sampler) const {
        return std::min(float((double(i) + double(sampler.next_1d())) / double(n)), 0x1.fffffep-1f);
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

template <typename Body> void for_each_sample(uint64_t n, const BoundaryOptions& options, uint64_t salt, const Body& body) {
    constexpr int chunks = 16;
    tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency());
    arena.execute([&] {
        tbb::parallel_for(0, chunks, [&](int c) {
            Sampler sampler;
            for (uint64_t i = n * c / chunks; i < n * (c + 1) / chunks; ++i) {
                if ((i & 1023) == 0) check_interrupt();
                sampler.start(options.seed ^ salt, i, 0);
                body(c, i, sampler);
            }
        });
    });
}

// The number of boundary samples: `count`, or the budget per pixel times the number of pixels.
inline uint64_t sample_count(const Film& film, const BoundaryOptions& options, uint64_t count) {
    return count > 0 ? count : uint64_t(film.width) * film.height * uint64_t(options.samples_per_pixel);
}

} // namespace detail

// Forward mode: Σ_samples P_j(s) weight dv/dθ / N for every pixel j. `sample(BoundarySampleIndex, Sampler&,
// RayCounter&)` draws the i-th of the N BoundarySamples (recording its velocities on the thread's tape) from a
// sampler started for it; N is `count`, or samples_per_pixel × the number of pixels.
template <typename SampleFn>
Image boundary_derivative(const Scene& scene, const Parameters& params, const BoundaryOptions& options, uint64_t salt,
                          const SampleFn& sample, uint64_t count = 0) {
    const Film& film = *scene.sensor->film;
    const uint64_t n_samples = detail::sample_count(film, options, count);
    const double n = double(n_samples);
    std::vector<Image> chunks(16, Image(film.width, film.height));
    std::array<SampleCost, 16> costs{};
    const std::vector<float> direction = tape_direction(params);
    detail::for_each_sample(n_samples, options, salt, [&](int c, uint64_t i, Sampler& sampler) {
        thread_local std::vector<float> tangent;
        Tape& tape = Tape::current();
        tape.clear();
        RayCounter rays;
        const BoundarySample b = sample(BoundarySampleIndex{i, n_samples}, sampler, rays);
        costs[c] += SampleCost{1, rays.rays, tape.size()};
        if (b.usable()) {
            tape.forward(direction.data(), tangent);
            bool finite = true;
            for (int k = 0; k < b.n_splats; ++k) finite = finite && std::isfinite(tangent[b.splats[k].velocity.id]);
            for (int k = 0; k < b.n_splats && finite; ++k) {
                const BoundarySample::Splat& splat = b.splats[k];
                const Color3f value = splat.weight * float(double(tangent[splat.velocity.id]) / n);
                for_each_pixel_in_footprint(film, splat.s, [&](int x, int y, float w) { chunks[c].at(x, y) += value * w; });
            }
            costs[c].dropped += !finite;
        } else {
            costs[c].dropped += b.n_splats > 0; // a non-finite weight
        }
        tape.clear();
    });
    Image result(film.width, film.height);
    for (const Image& chunk : chunks)
        for (size_t i = 0; i < result.pixels.size(); ++i) result.pixels[i] += chunk.pixels[i];
    if (options.cost)
        for (const SampleCost& c : costs) *options.cost += c;
    return result;
}

// Reverse mode: adds Σ_samples (Σ_j adjoint_j P_j(s)) · weight · dv/dθ / N to `gradient`.
template <typename SampleFn>
void boundary_gradient(const Scene& scene, const Parameters& params, const Image& adjoint,
                       const BoundaryOptions& options, uint64_t salt, const SampleFn& sample,
                       std::vector<double>& gradient, uint64_t count = 0) {
    const Film& film = *scene.sensor->film;
    const uint64_t n_samples = detail::sample_count(film, options, count);
    const double n = double(n_samples);
    const size_t dim = size_t(params.tape_dimension());
    tbb::enumerable_thread_specific<std::vector<double>> local([dim] { return std::vector<double>(dim, 0.0); });
    std::array<SampleCost, 16> costs{};
    detail::for_each_sample(n_samples, options, salt, [&](int c, uint64_t i, Sampler& sampler) {
        thread_local std::vector<float> scratch;
        thread_local std::vector<std::pair<int32_t, float>> seeds;
        Tape& tape = Tape::current();
        tape.clear();
        RayCounter rays;
        const BoundarySample b = sample(BoundarySampleIndex{i, n_samples}, sampler, rays);
        costs[c] += SampleCost{1, rays.rays, tape.size()};
        if (b.usable()) {
            seeds.clear();
            for (int k = 0; k < b.n_splats; ++k) {
                const BoundarySample::Splat& splat = b.splats[k];
                double seed = 0;
                for_each_pixel_in_footprint(film, splat.s, [&](int x, int y, float w) { seed += w * dot(adjoint.at(x, y), splat.weight); });
                seeds.emplace_back(splat.velocity.id, float(seed / n));
            }
            costs[c].dropped += !tape.backward(seeds, local.local().data(), scratch);
        } else {
            costs[c].dropped += b.n_splats > 0; // a non-finite weight
        }
        tape.clear();
    });
    add_chained_gradient(params, local, gradient);
    if (options.cost)
        for (const SampleCost& c : costs) *options.cost += c;
}

} // namespace penumbra
