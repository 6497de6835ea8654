// Entropic optimal transport of the DPM-G matching loss (core/sinkhorn.h) at the paper's size: all pixels of
// an N x N rendering matched to all pixels of an N x N target as 5-D points (RGB + xy), blur 0.01.
//  - BM_SinkhornIteration/N/threads: one Sinkhorn iteration and the matching at ε = blur² (three passes over
//    the N⁴ costs);
//  - BM_SinkhornAnnealed/N/threads: the ε-scaling solve of the paper's setup (GeomLoss, scaling 0.9) with one
//    iteration at the final ε.
// The images are the ones of scripts/compare_sinkhorn_pot.py (a coloured blob on a gradient, moved and
// recoloured in the target), so the numbers compare with POT's there.
//
// Usage: build/penumbra_bench_sinkhorn [--benchmark_filter=...]
#include "core/sinkhorn.h"

#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <cmath>

using namespace penumbra;

namespace {

// An N x N image as 5-D points: background (0.2u, 0.2v, 0.1) plus a Gaussian blob of colour `rgb` at (cx,
// cy).
Points5 blob_image(int n, double cx, double cy, double sigma, const Eigen::Vector3d& rgb) {
    Points5 p(n * n, 5);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const int i = y * n + x;
            const double u = (x + 0.5) / n, v = (y + 0.5) / n;
            const double k = std::exp(-((u - cx) * (u - cx) + (v - cy) * (v - cy)) / (2 * sigma * sigma));
            p.row(i) << 0.2 * u + rgb[0] * k, 0.2 * v + rgb[1] * k, 0.1 + rgb[2] * k, u, v;
        }
    return p;
}

void run(benchmark::State& state, const SinkhornOptions& options) {
    const int n = int(state.range(0));
    const Points5 x = blob_image(n, 0.35, 0.40, 0.08, {0.9, 0.7, 0.2});
    const Points5 y = blob_image(n, 0.62, 0.58, 0.06, {0.8, 0.8, 0.3});
    const Eigen::VectorXd w = Eigen::VectorXd::Ones(n * n);
    tbb::task_arena arena(int(state.range(1)));
    SinkhornResult r;
    for (auto _ : state)
        arena.execute([&] { r = sinkhorn(x, w, y, w, options); });
    state.counters["iterations"] = r.annealing_steps + r.iterations;
    state.counters["marginal_error"] = r.marginal_error;
}

void BM_SinkhornIteration(benchmark::State& state) {
    SinkhornOptions o;
    o.scaling = 0;
    o.tolerance = 0;
    o.max_iterations = 1;
    run(state, o);
}

void BM_SinkhornAnnealed(benchmark::State& state) {
    SinkhornOptions o;
    o.max_iterations = 1;
    run(state, o);
}

} // namespace

BENCHMARK(BM_SinkhornIteration)->ArgsProduct({{64, 128}, {1, 2}})->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_SinkhornAnnealed)->ArgsProduct({{64, 128}, {1, 2}})->Unit(benchmark::kSecond)->Iterations(1);

BENCHMARK_MAIN();
