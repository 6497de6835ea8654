// Stratified sample positions within a pixel (or any unit square): the samples of one pixel cover it evenly
// instead of independently, which removes most of the variance of what is smooth within the pixel and makes the
// number of samples on either side of an edge through it nearly deterministic.
#pragma once
#include "core/rng.h"
#include "core/vector.h"

#include <cmath>
#include <cstdint>

namespace penumbra {

// A pseudo-random permutation of [0, n) selected by `seed`: cycle walking over an invertible hash of the
// enclosing power-of-two range (xor-shifts and odd multiplications are bijections modulo a power of two).
inline uint32_t permute(uint32_t i, uint32_t n, uint32_t seed) {
    if (n <= 1) return 0;
    int bits = 1;
    while ((1u << bits) < n) ++bits;
    const uint32_t mask = bits >= 32 ? ~0u : (1u << bits) - 1u;
    const uint32_t shift = uint32_t(bits + 1) / 2;
    uint64_t key = seed;
    do {
        for (int round = 0; round < 4; ++round) {
            key = mix_bits(key + 0x9E3779B97F4A7C15ULL);
            i = (i ^ uint32_t(key)) & mask;
            i = (i * (uint32_t(key >> 32) | 1u)) & mask;
            i ^= i >> shift;
        }
        key = seed;
    } while (i >= n);
    return i;
}

// Sample m of n stratified over [0,1)², jittered by u ∈ [0,1)²: in a k × k grid of cells when n = k², else
// n-rooks (one of n columns and one of n rows each, the rows permuted by `seed`).
inline Vec2f stratified_2d(uint32_t m, uint32_t n, uint32_t seed, const Vec2f& u) {
    const uint32_t k = uint32_t(std::lround(std::sqrt(double(n))));
    if (k * k == n) return Vec2f((float(m % k) + u.x) / float(k), (float(m / k) + u.y) / float(k));
    return Vec2f((float(m) + u.x) / float(n), (float(permute(m, n, seed)) + u.y) / float(n));
}

// Sample `index` of the `count` samples of a pixel, its strata permuted per (seed, pixel).
struct PixelStratum {
    uint32_t index, count, seed;
    PixelStratum(int sample, int samples, uint64_t seed_value, uint64_t pixel)
        : index(uint32_t(sample)), count(uint32_t(samples)), seed(uint32_t(mix_bits(seed_value ^ pixel))) {}
    Vec2f operator()(const Vec2f& u) const { return stratified_2d(index, count, seed, u); }
};

} // namespace penumbra
