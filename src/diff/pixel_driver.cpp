#include "diff/pixel_driver.h"

#include "core/batch_stats.h"
#include "core/interrupt.h"
#include "core/seconds.h"
#include "diff/vertex_normals.h"
#include "render/light_medium.h"
#include "render/tiles.h"

#include <tbb/enumerable_thread_specific.h>

namespace penumbra {

namespace {

bool finite(const Color3<Var>& c) {
    return std::isfinite(c.x.v) && std::isfinite(c.y.v) && std::isfinite(c.z.v);
}

class StatelessTile final : public TileSamples {
  public:
    explicit StatelessTile(const SampleFunction& f) : f_(f) {}
    Color3<Var> sample(Sampler& sampler, const PixelSample& s, RayCounter& rays) override {
        return f_(sampler, s, rays);
    }

  private:
    const SampleFunction& f_;
};

// Every camera sample of the film, tiles in parallel: `make(tile)` gives a tile's pixel accumulator, whose
// begin(x, y) and end(x, y) run around each pixel and add(value) on each finite sample (its tape still
// recorded), which returns false when the sample's derivative is not finite. Samples with a non-finite value
// or derivative are dropped and counted (SampleCost::dropped).
template <typename MakePixels>
void for_each_sample(const PixelLoop& loop, uint64_t seed, const std::function<void(float)>& progress,
                     SharedSampleCost& cost, MakePixels&& make) {
    const Film& film = *loop.scene.sensor->film;
    const int streams = loop.antithetic ? (loop.options.spp + 1) / 2 : loop.options.spp;
    for_each_tile(
        film.width, film.height, loop.options.threads,
        [&](int x0, int y0, int x1, int y1) {
            Sampler sampler(*loop.scene.sensor->sampler, streams);
            RayCounter rays;
            uint64_t tape_nodes = 0, dropped = 0;
            Tape& tape = Tape::current();
            const std::unique_ptr<TileSamples> tile = loop.tiles();
            auto pixels = make(*tile);
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) {
                    const uint64_t pixel = uint64_t(y) * film.width + x;
                    pixels.begin(x, y);
                    for (int m = 0; m < loop.options.spp; ++m) {
                        check_interrupt(); // per sample: at a large spp, a pixel takes seconds
                        sampler.start(seed, pixel, uint64_t(loop.antithetic ? m / 2 : m));
                        tape.clear();
                        const Color3<Var> v = tile->sample(sampler, {x, y, pixel, m, seed}, rays);
                        tape_nodes += tape.size();
                        if (!finite(v) || !pixels.add(v)) ++dropped;
                    }
                    pixels.end(x, y);
                }
            tape.clear();
            cost.add({uint64_t(x1 - x0) * uint64_t(y1 - y0) * uint64_t(loop.options.spp), rays.rays, tape_nodes,
                      dropped});
        },
        progress);
}

struct PixelSums {
    Image primal, derivative;
};

// A tile's forward-mode sums: each sample's tangents along params.direction(), corrected by the tile.
struct ForwardPixels {
    ForwardPixels(const PixelLoop& l, const std::vector<float>& d, TileSamples& t, PixelSums& o)
        : loop(l), direction(d), tile(t), out(o) {}
    const PixelLoop& loop;
    const std::vector<float>& direction; // tape_direction(loop.params)
    TileSamples& tile;
    PixelSums& out;
    std::vector<float> tangent;
    Vec3d primal{0.0}, derivative{0.0};

    void begin(int x, int y) {
        primal = derivative = Vec3d(0.0);
        tile.begin_pixel(x, y);
    }
    bool add(const Color3<Var>& v) {
        Tape::current().forward(direction.data(), tangent);
        Vec3d d(tangent_of(v.x, tangent), tangent_of(v.y, tangent), tangent_of(v.z, tangent));
        tile.correct(tangent, d);
        if (!is_finite(Vec3f(d))) return false;
        primal += Vec3d(v.x.v, v.y.v, v.z.v);
        derivative += d;
        return true;
    }
    void end(int x, int y) {
        out.primal.at(x, y) = Color3f(primal / double(loop.options.spp));
        out.derivative.at(x, y) = Color3f(derivative / double(loop.options.spp));
        tile.end_pixel();
    }
};

// A tile's reverse-mode pass: each sample's adjoint ∂L/∂I / spp swept back into the thread's gradient.
struct ReversePixels {
    ReversePixels(const PixelLoop& l, const Image& a, std::vector<double>& g, Image& p)
        : loop(l), adjoint(a), gradient(g), primal_out(p) {}
    const PixelLoop& loop;
    const Image& adjoint;
    std::vector<double>& gradient;
    Image& primal_out;
    std::vector<float> scratch;
    std::vector<std::pair<int32_t, float>> seeds = std::vector<std::pair<int32_t, float>>(3);
    Color3f a{0.f};
    Vec3d primal{0.0};

    void begin(int x, int y) {
        a = adjoint.at(x, y) * (1.f / float(loop.options.spp));
        primal = Vec3d(0.0);
    }
    bool add(const Color3<Var>& v) {
        seeds[0] = {v.x.id, a.x};
        seeds[1] = {v.y.id, a.y};
        seeds[2] = {v.z.id, a.z};
        if (!Tape::current().backward(seeds, gradient.data(), scratch)) return false;
        primal += Vec3d(v.x.v, v.y.v, v.z.v);
        return true;
    }
    void end(int x, int y) { primal_out.at(x, y) = Color3f(primal / double(loop.options.spp)); }
};

BoundaryOptions film_edge_options(const PixelLoop& loop, uint64_t seed, SampleCost& cost) {
    BoundaryOptions bo;
    bo.seed = seed;
    bo.threads = loop.options.threads;
    bo.path = loop.options.path;
    bo.first_vertex = FirstVertex::Material;
    bo.cost = &cost;
    return bo;
}

} // namespace

void require_film(const Scene& scene, const Parameters& params) {
    if (params.dimension() == 0) throw Error("no parameter is enabled for differentiation");
    if (!scene.sensor || !scene.sensor->film) throw Error("the scene has no sensor");
}

void check_adjoint_size(const Film& film, const Image& adjoint) {
    if (adjoint.width != film.width || adjoint.height != film.height)
        throw Error("gradient: the adjoint image is " + std::to_string(adjoint.width) + "x" +
                    std::to_string(adjoint.height) + ", the film " + std::to_string(film.width) + "x" +
                    std::to_string(film.height));
}

void require_no_media(const Scene& scene) {
    if (scene_has_media(scene))
        throw Error("the scene has participating media, which this method does not differentiate: use the psdr "
                    "method (the default)");
}

TileSamplesFactory per_sample(SampleFunction f) {
    return [f = std::move(f)] { return std::make_unique<StatelessTile>(f); };
}

DerivativeImage pixel_derivative(const PixelLoop& loop) {
    if (loop.options.spp <= 0 || loop.options.batches <= 0) throw Error("derivative: spp and batches must be positive");
    const Film& film = *loop.scene.sensor->film;
    const int B = loop.options.batches;
    ImageBatches primal, derivative;
    SharedSampleCost cost;
    const std::vector<float> direction = tape_direction(loop.params);
    for (int b = 0; b < B; ++b) {
        auto progress = loop.options.progress
                            ? std::function<void(float)>([&, b](float f) { loop.options.progress((b + f) / B); })
                            : std::function<void(float)>();
        const uint64_t seed = loop.options.seed + 0x9E3779B97F4A7C15ULL * uint64_t(b);
        PixelSums s{Image(film.width, film.height), Image(film.width, film.height)};
        for_each_sample(loop, seed, progress, cost,
                        [&](TileSamples& tile) { return ForwardPixels(loop, direction, tile, s); });
        if (loop.film_edge) {
            SampleCost edge_cost;
            const Image edges =
                loop.film_edge(seed).derivative(loop.params, film_edge_options(loop, seed, edge_cost));
            cost.add({0, edge_cost.rays, edge_cost.tape_nodes, edge_cost.dropped});
            for (size_t i = 0; i < edges.pixels.size(); ++i)
                s.derivative.pixels[i] += edges.pixels[i];
        }
        primal.add(s.primal);
        derivative.add(s.derivative);
    }
    DerivativeImage result;
    result.derivative = derivative.mean();
    result.stderr_img = derivative.standard_error();
    result.mean_stderr = derivative.mean_standard_error();
    result.block_stderr = derivative.block_standard_errors();
    result.primal = primal.mean();
    result.description = loop.description;
    result.cost = cost.get();
    result.seconds = seconds_since(loop.start);
    result.terms.push_back({loop.term, result.derivative, result.stderr_img, result.cost, result.seconds,
                            result.mean_stderr, result.block_stderr});
    return result;
}

Gradient pixel_gradient(const PixelLoop& loop, const Image& adjoint) {
    const Film& film = *loop.scene.sensor->film;
    check_adjoint_size(film, adjoint);
    if (loop.options.spp <= 0) throw Error("gradient: spp must be positive");
    const size_t dim = size_t(loop.params.tape_dimension());
    tbb::enumerable_thread_specific<std::vector<double>> gradients(
        [dim] { return std::vector<double>(dim, 0.0); });
    Gradient result;
    result.values.assign(size_t(loop.params.dimension()), 0.0);
    result.primal = Image(film.width, film.height);
    result.description = loop.description;
    if (!loop.unwarped_delta_lights.empty())
        for (const auto& e : loop.scene.emitters)
            if (e->is_delta() && !e->is_infinite()) {
                result.warnings.push_back(
                    "method " + loop.unwarped_delta_lights +
                    " does not see the motion of shadows cast from point and spot lights");
                break;
            }
    SharedSampleCost cost;
    for_each_sample(loop, loop.options.seed, loop.options.progress, cost, [&](TileSamples&) {
        return ReversePixels(loop, adjoint, gradients.local(), result.primal);
    });
    if (loop.film_edge) {
        SampleCost edge_cost;
        loop.film_edge(loop.options.seed).gradient(loop.params, adjoint,
                                           film_edge_options(loop, loop.options.seed, edge_cost), result.values);
        cost.add({0, edge_cost.rays, edge_cost.tape_nodes, edge_cost.dropped});
    }
    result.cost = cost.get();
    add_chained_gradient(loop.params, gradients, result.values);
    result.seconds = seconds_since(loop.start);
    return result;
}

bool filter_jumps(const ReconstructionFilter& filter) { return filter.plugin == "box"; }

int film_edge_strata(const Film& film, int spp) {
    return filter_jumps(*film.rfilter) ? std::max(1, spp / 2) : spp;
}

} // namespace penumbra
