// The `independent` sampler: one RNG stream per (seed, pixel, sample index), so that images are
// bit-identical for a given seed whatever the thread count or tile order.
#pragma once
#include "core/rng.h"
#include "core/vector.h"

namespace penumbra {

class Sampler {
public:
    Sampler() = default;
    // Positions the sampler at the start of sample `sample_index` of the pixel with linear index `pixel`.
    void start(uint64_t seed, uint64_t pixel, uint64_t sample_index) {
        rng_.seed(mix_bits(seed * 0x9E3779B97F4A7C15ULL + pixel), mix_bits(sample_index + 0x632BE59BD9B4E019ULL * seed));
    }
    float next_1d() { return rng_.next_float(); }
    Vec2f next_2d() {
        const float a = rng_.next_float();
        return {a, rng_.next_float()};
    }

private:
    PCG32 rng_;
};

} // namespace penumbra
