// The per-dimension sample patterns of the stratified, multi-jittered, orthogonal-array and low-discrepancy
// samplers. Each function maps a sample's slot in its pixel's set of `n` samples (already a pure function of
// seed, pixel and sample index) to a coordinate; the randomization comes from hashed seeds and jitter values
// passed in, so the pattern functions themselves are deterministic.
#pragma once
#include "core/rng.h"
#include "core/vector.h"

#include <cstdint>

namespace penumbra {

// Uniform float in [0,1) from the top 24 bits of a 32-bit value (exact, never rounds up to 1).
inline float unit_float(uint32_t bits) { return float(bits >> 8) * 0x1p-24f; }

// A seed for the k-th permutation drawn from `seed` (a cheap 32-bit avalanche of seed and k).
inline uint32_t sub_seed(uint32_t seed, uint32_t k) {
    uint32_t h = (seed ^ (k * 0x9E3779B9u)) * 0x85ebca6bu;
    h ^= h >> 13;
    h *= 0xc2b2ae35u;
    return h ^ (h >> 16);
}

// A pseudo-random permutation π(i) of [0, n) chosen by `seed` (n < 2^31): cycle walking over rounds of
// bijections of the enclosing power-of-two range (xor / add a key, multiply by an odd constant, xor-shift),
// the construction of Kensler's permute() ("Correlated Multi-Jittered Sampling", 2013) with rounds of our
// own. Cheap: no hashing per round.
inline uint32_t shuffle(uint32_t i, uint32_t n, uint32_t seed) {
    if (n <= 1) return 0;
    const uint32_t bits = 32u - uint32_t(__builtin_clz(n - 1)), mask = (1u << bits) - 1u,
                   half = (bits + 1) / 2;
    const uint32_t k1 = seed * 0x9E3779B9u + 0x7f4a7c15u;
    do {
        i = ((i ^ seed) * 0xa3c59ac3u) & mask;
        i ^= i >> half;
        i = ((i + k1) * 0x2c9277b5u) & mask;
        i ^= i >> half;
        i = ((i ^ (seed >> 11)) * 0x297a2d39u) & mask;
        i ^= i >> half;
        i = ((i + (k1 >> 9)) * 0x5bd1e995u) & mask;
        i ^= i >> half;
    } while (i >= n);
    // A rotation by a seeded offset makes every π(i) uniform over [0, n) across seeds (the rounds above alone
    // favour some values when n is not a power of two): each sample's strata are then uniformly distributed,
    // which is what makes the stratified estimators unbiased.
    const uint32_t offset = uint32_t((uint64_t(sub_seed(seed, 0x51ed)) * n) >> 32);
    return uint32_t((uint64_t(i) + offset) % n);
}

// Jittered 1D stratification: slot m of n lands in stratum π(m) of [0,1) (π a permutation chosen by `seed`).
inline float stratified_1d(uint32_t m, uint32_t n, uint32_t seed, float jitter) {
    return (float(shuffle(m, n, seed)) + jitter) / float(n);
}

// Jittered 2D stratification on an r × r grid (n = r²): slot m lands in cell π(m) (Mitsuba's `stratified`).
inline Vec2f stratified_grid_2d(uint32_t m, uint32_t r, uint32_t seed, const Vec2f& jitter) {
    const uint32_t cell = shuffle(m, r * r, seed);
    return Vec2f((float(cell % r) + jitter.x) / float(r), (float(cell / r) + jitter.y) / float(r));
}

// Correlated multi-jittered sampling (Kensler 2013): slot m of n = cols × rows sits in cell
// (i, j) = (s mod cols, s div cols) of the canonical arrangement, s = π(m); within its cell it occupies
// sub-column σ_x(j) and sub-row σ_y(i), one permutation each shared by all cells (the "correlated" variant).
// The points are stratified in the cols × rows grid and in n strata along each axis.
inline Vec2f multijitter_2d(uint32_t m, uint32_t cols, uint32_t rows, uint32_t seed, const Vec2f& jitter) {
    const uint32_t s = shuffle(m, cols * rows, seed);
    const uint32_t i = s % cols, j = s / cols;
    const uint32_t sx = shuffle(j, rows, sub_seed(seed, 1)), sy = shuffle(i, cols, sub_seed(seed, 2));
    return Vec2f((float(i) + (float(sx) + jitter.x) / float(rows)) / float(cols),
                 (float(j) + (float(sy) + jitter.y) / float(cols)) / float(rows));
}

// Column c ∈ [0, p] of the Bose orthogonal array OA(p², p + 1, p, 2) (Bose 1938; Jarosz et al. 2019,
// "Orthogonal Array Sampling for Monte Carlo Rendering") at row (a0, a1) ∈ [0,p)²: a0 + c·a1 mod p for c < p,
// and a1 for c = p. Any two columns are orthogonal: their value pairs run over all p² combinations once.
inline uint32_t bose_column(uint32_t a0, uint32_t a1, uint32_t c, uint32_t p) {
    return c == p ? a1 : (a0 + c * a1) % p;
}

// Dimension d ≤ p of a strength-2 orthogonal-array sample (Jarosz et al. 2019, multi-jittered
// flavour): the stratum is column d, the sub-stratum the next column d + 1 (mod p + 1), each permuted per
// dimension, so every dimension is stratified in p² intervals and every pair of dimensions in a p × p grid.
inline float orthogonal_1d(uint32_t row, uint32_t p, uint32_t d, uint32_t seed, float jitter) {
    const uint32_t a0 = row / p, a1 = row % p;
    const uint32_t stratum = shuffle(bose_column(a0, a1, d, p), p, sub_seed(seed, 1));
    const uint32_t sub = shuffle(bose_column(a0, a1, (d + 1) % (p + 1), p), p, sub_seed(seed, 2));
    return (float(stratum) + (float(sub) + jitter) / float(p)) / float(p);
}

// Radical inverse in base 2 of i as a 32-bit fraction (van der Corput): the first dimension of the Sobol'
// (0,2)-sequence.
inline uint32_t van_der_corput(uint32_t i) {
    i = (i << 16) | (i >> 16);
    i = ((i & 0x00ff00ffu) << 8) | ((i & 0xff00ff00u) >> 8);
    i = ((i & 0x0f0f0f0fu) << 4) | ((i & 0xf0f0f0f0u) >> 4);
    i = ((i & 0x33333333u) << 2) | ((i & 0xccccccccu) >> 2);
    return ((i & 0x55555555u) << 1) | ((i & 0xaaaaaaaau) >> 1);
}

// The second dimension of the Sobol' (0,2)-sequence: generator matrix with direction numbers v_0 = 2^31,
// v_{k+1} = v_k ⊕ (v_k >> 1) (Pascal's triangle mod 2), x = ⊕_k bit_k(i) v_k.
inline uint32_t sobol_second(uint32_t i) {
    uint32_t x = 0;
    for (uint32_t v = 1u << 31; i; i >>= 1, v ^= v >> 1)
        if (i & 1u) x ^= v;
    return x;
}

// A nested (Owen-style) scramble of a 32-bit fraction: after bit reversal every step flips each bit by a
// function of the bits below it only (carries of an addition, odd multiplications, xor with an even
// multiple), i.e. of the more significant digits of the fraction; so every elementary interval maps onto one
// of the same size (the hash-based construction of Laine and Karras 2011, with constants of our own).
inline uint32_t nested_scramble(uint32_t v, uint32_t seed) {
    v = van_der_corput(v); // bit reversal
    v += seed;
    v ^= v * 0x2c1b3c6eu;
    v *= (seed >> 8) | 1u;
    v ^= v * 0x91e10da4u;
    v += seed * 0x9E3779B9u;
    v ^= v * 0x7feb352cu;
    // A final random digit flip (also nested) makes the scrambled value uniform across seeds.
    return van_der_corput(v) ^ sub_seed(seed, 0x5c4a);
}

// Point `i` of the randomized (0,2)-sequence: van der Corput and Sobol' second dimension, each
// nested-scrambled. Its first 4^k points form a (0, 2k, 2)-net: one point in every elementary interval of
// area 4^-k.
inline Vec2f sobol02_2d(uint32_t i, uint32_t seed_x, uint32_t seed_y) {
    return Vec2f(unit_float(nested_scramble(van_der_corput(i), seed_x)),
                 unit_float(nested_scramble(sobol_second(i), seed_y)));
}

} // namespace penumbra
