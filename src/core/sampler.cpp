#include "core/sampler.h"

#include "core/sample_patterns.h"

#include <algorithm>

namespace penumbra {

namespace {

uint32_t square_side(uint32_t spp) { // the smallest r with r² ≥ spp
    uint32_t r = 1;
    while (uint64_t(r) * r < spp)
        ++r;
    return r;
}

bool is_prime(uint32_t x) {
    for (uint32_t d = 2; d * d <= x; ++d)
        if (x % d == 0) return false;
    return x >= 2;
}

uint32_t prime_side(uint32_t spp) { // the smallest prime p with p² ≥ spp
    uint32_t p = 2;
    while (uint64_t(p) * p < spp || !is_prime(p))
        ++p;
    return p;
}

uint32_t power_of_four(uint32_t spp) { // the smallest 4^k ≥ max(spp, 4)
    uint32_t n = 4;
    while (n < spp && n < (1u << 30))
        n *= 4;
    return n;
}

// The number of samples the sampler's pattern supports, ≥ spp.
uint32_t pattern_size(SamplerType type, uint32_t spp) {
    switch (type) {
    case SamplerType::Stratified:
        return square_side(spp) * square_side(spp);
    case SamplerType::Orthogonal:
        return prime_side(spp) * prime_side(spp);
    case SamplerType::LowDiscrepancy:
        return power_of_four(spp);
    default:
        return spp;
    }
}

} // namespace

int SamplerSpec::rounded(int spp) const {
    spp = std::clamp(spp, 1, kMaxSampleCount);
    if (type != SamplerType::Multijitter) return int(pattern_size(type, uint32_t(spp)));
    // Mitsuba's multijitter: a cols × rows × rows arrangement with rows = ⌊∛spp⌋, cols = ⌈spp / rows²⌉.
    uint32_t rows = 1;
    while ((rows + 1) * (rows + 1) * (rows + 1) <= uint32_t(spp))
        ++rows;
    const uint32_t cols = (uint32_t(spp) + rows * rows - 1) / (rows * rows);
    return int(cols * rows * rows);
}

const char* sampler_type_name(SamplerType type) {
    switch (type) {
    case SamplerType::Stratified:
        return "stratified";
    case SamplerType::Multijitter:
        return "multijitter";
    case SamplerType::Orthogonal:
        return "orthogonal";
    case SamplerType::LowDiscrepancy:
        return "ldsampler";
    default:
        return "independent";
    }
}

Sampler::Sampler(const SamplerSpec& spec, int samples)
    : type_(spec.type), n_(pattern_size(spec.type, uint32_t(std::clamp(samples, 1, kMaxSampleCount)))),
      seed_offset_(spec.seed), jitter_(spec.jitter) {
    if (type_ == SamplerType::Stratified) cols_ = rows_ = square_side(n_);
    if (type_ == SamplerType::Orthogonal) cols_ = rows_ = prime_side(n_);
    if (type_ == SamplerType::Multijitter) { // the most nearly square grid cols × rows = n
        rows_ = square_side(n_);
        while (n_ % rows_ != 0)
            --rows_;
        cols_ = n_ / rows_;
    }
}

void Sampler::start(uint64_t seed, uint64_t pixel, uint64_t sample_index) {
    seed += seed_offset_;
    if (type_ == SamplerType::Independent) {
        rng_.seed(mix_bits(seed * 0x9E3779B97F4A7C15ULL + pixel),
                  mix_bits(sample_index + 0x632BE59BD9B4E019ULL * seed));
        return;
    }
    key_ = mix_bits(mix_bits(mix_bits(seed) + pixel) + sample_index / n_);
    slot_ = uint32_t(sample_index % n_);
    dim_ = 0;
    // The orthogonal array's rows are shuffled once per pixel set: all dimensions of a sample share its row.
    if (type_ == SamplerType::Orthogonal)
        row_ = shuffle(slot_, n_, uint32_t(mix_bits(key_ ^ 0x5851F42D4C957F2DULL)));
}

float Sampler::jitter(uint32_t axis) const {
    if (!jitter_) return 0.5f;
    return unit_float(
        uint32_t(mix_bits(key_ + 0xD1B54A32D192ED03ULL * slot_ + 0x8CB92BA72F3D8DD7ULL * (2 * dim_ + axis))));
}

float Sampler::next_1d() {
    float u = 0.f;
    const uint32_t seed = dimension_seed();
    switch (type_) {
    case SamplerType::Independent:
        return rng_.next_float();
    case SamplerType::Orthogonal:
        // Beyond the array's p + 1 columns, dimensions are stratified on their own (a Latin hypercube).
        u = dim_ <= cols_ ? orthogonal_1d(row_, cols_, dim_, seed, jitter(0))
                          : stratified_1d(slot_, n_, seed, jitter(0));
        break;
    case SamplerType::LowDiscrepancy:
        u = unit_float(nested_scramble(van_der_corput(shuffle(slot_, n_, seed)), sub_seed(seed, 3)));
        break;
    default:
        u = stratified_1d(slot_, n_, seed, jitter(0));
        break;
    }
    ++dim_;
    return u;
}

Vec2f Sampler::next_2d() {
    if (type_ == SamplerType::Independent) {
        const float a = rng_.next_float();
        return {a, rng_.next_float()};
    }
    if (type_ == SamplerType::Orthogonal) {
        const float a = next_1d();
        return {a, next_1d()};
    }
    const uint32_t seed = dimension_seed();
    Vec2f u;
    if (type_ == SamplerType::Stratified)
        u = stratified_grid_2d(slot_, cols_, seed, Vec2f(jitter(0), jitter(1)));
    if (type_ == SamplerType::Multijitter)
        u = multijitter_2d(slot_, cols_, rows_, seed, Vec2f(jitter(0), jitter(1)));
    if (type_ == SamplerType::LowDiscrepancy)
        u = sobol02_2d(shuffle(slot_, n_, seed), sub_seed(seed, 3), sub_seed(seed, 4));
    ++dim_;
    return u;
}

} // namespace penumbra
