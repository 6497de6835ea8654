// The work an estimator did, counted deterministically (unlike wall time, it does not depend on the machine or
// the thread count), so that sample budgets derived from it keep results reproducible per seed.
#pragma once
#include <atomic>
#include <cstdint>

namespace penumbra {

struct SampleCost {
    uint64_t samples = 0;
    uint64_t rays = 0;        // rays cast (intersection and shadow)
    uint64_t tape_nodes = 0;  // AD tape nodes recorded (each also swept once)
    // The NaN policy: samples whose value or derivative was not finite, left out of the estimate (and counted
    // in `samples`).
    uint64_t dropped = 0;

    // Cost in units of one ray: rays, plus AD tape nodes (each recorded, then swept forward or backward), plus
    // what a sample does besides (sampling edges, lights and lobes, shading). Fitted to per-term timings of
    // `penumbra derivative` (which prints them) on the occluder, rectangle and glossy-shadow scenes at 64²: a ray
    // ~0.15 µs, a tape node ~2.5 ns, a sample's other work ~0.05–0.2 µs; the model is within a factor 1.5 of
    // every term's measured time there.
    static constexpr double TapeNodesPerRay = 64.0, RaysPerSample = 0.5;
    double units() const { return double(rays) + double(tape_nodes) / TapeNodesPerRay + double(samples) * RaysPerSample; }

    SampleCost& operator+=(const SampleCost& o) {
        samples += o.samples, rays += o.rays, tape_nodes += o.tape_nodes, dropped += o.dropped;
        return *this;
    }
};

// Integer counts summed from worker threads (the total does not depend on the order).
struct SharedSampleCost {
    std::atomic<uint64_t> samples{0}, rays{0}, tape_nodes{0}, dropped{0};
    void add(const SampleCost& c) {
        samples += c.samples, rays += c.rays, tape_nodes += c.tape_nodes, dropped += c.dropped;
    }
    SampleCost get() const { return {samples.load(), rays.load(), tape_nodes.load(), dropped.load()}; }
};

} // namespace penumbra
