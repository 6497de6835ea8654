// Stratified sample positions within a pixel (or any unit square): the samples of one pixel cover it evenly
// instead of independently, which removes most of the variance of what is smooth within the pixel and makes the
// number of samples on either side of an edge through it nearly deterministic.
#pragma once
#include "core/rng.h"
#include "core/sample_patterns.h"
#include "core/vector.h"

#include <cmath>
#include <cstdint>

namespace penumbra {

// Sample m of n stratified over [0,1)², jittered by u ∈ [0,1)²: in a k × k grid of cells when n = k², else
// n-rooks (one of n columns and one of n rows each, the rows permuted by `seed` with shuffle(), whose
// uniform marginals keep the estimate unbiased).
inline Vec2f stratified_2d(uint32_t m, uint32_t n, uint32_t seed, const Vec2f& u) {
    const uint32_t k = uint32_t(std::lround(std::sqrt(double(n))));
    if (k * k == n) return Vec2f((float(m % k) + u.x) / float(k), (float(m / k) + u.y) / float(k));
    return Vec2f((float(m) + u.x) / float(n), (float(shuffle(m, n, seed)) + u.y) / float(n));
}

// Sample `index` of the `count` samples of a pixel, its strata permuted per (seed, pixel).
struct PixelStratum {
    uint32_t index, count, seed;
    PixelStratum(int sample, int samples, uint64_t seed_value, uint64_t pixel)
        : index(uint32_t(sample)), count(uint32_t(samples)), seed(uint32_t(mix_bits(seed_value ^ pixel))) {}
    Vec2f operator()(const Vec2f& u) const { return stratified_2d(index, count, seed, u); }
};

} // namespace penumbra
