// Samplers: the random numbers of one sample of one pixel, dimension after dimension (Mitsuba 3's Sampler).
// `independent` draws one RNG stream per (seed, pixel, sample index). The others (stratified, multijitter,
// orthogonal, ldsampler) spread the n samples of a pixel over each dimension: every value is a pure function
// of (seed, pixel, sample index, dimension), so images are bit-identical for a given seed whatever the thread
// count or tile order. Sample indices beyond n start a new, independently randomized set of n.
#pragma once
#include "core/rng.h"
#include "core/vector.h"

namespace penumbra {

// The largest number of samples per pixel a sampler accepts.
constexpr int kMaxSampleCount = 1 << 24;

enum class SamplerType { Independent, Stratified, Multijitter, Orthogonal, LowDiscrepancy };

// A sampler's description as loaded from a scene (Mitsuba 3 parameter names).
struct SamplerSpec {
    SamplerType type = SamplerType::Independent;
    int sample_count = 4; // samples per pixel, already rounded as the sampler requires
    uint64_t seed = 0;    // seed offset, added to the render seed
    bool jitter = true;   // random position within the finest stratum (else its centre)

    // The sample count the sampler actually uses when asked for `spp` (Mitsuba's set_sample_count rounding):
    // stratified: the next square; multijitter: cols · rows² with rows = ⌊∛spp⌋; orthogonal: p² for the
    // smallest prime p with p² ≥ spp; ldsampler: the next power of four ≥ 4; independent: spp.
    int rounded(int spp) const;
    // The effective samples per pixel of a render: `override_spp` rounded if positive, else sample_count.
    int effective_spp(int override_spp) const {
        return override_spp > 0 ? rounded(override_spp) : sample_count;
    }
};

const char* sampler_type_name(SamplerType type); // Mitsuba plugin name, e.g. "ldsampler"

class Sampler {
  public:
    Sampler() = default; // independent
    // A sampler of `spec`'s kind for `samples` samples per pixel: its sets hold the smallest number ≥ samples
    // its pattern supports (a square, p², a power of four; any number for multijitter and independent).
    Sampler(const SamplerSpec& spec, int samples);

    // Positions the sampler at the start of sample `sample_index` of the pixel with linear index `pixel`.
    void start(uint64_t seed, uint64_t pixel, uint64_t sample_index);
    float next_1d();
    Vec2f next_2d();

  private:
    // The seed of the current dimension's permutations and scrambles.
    uint32_t dimension_seed() const { return uint32_t(mix_bits(key_ + 0x9E3779B97F4A7C15ULL * (dim_ + 1))); }
    float
    jitter(uint32_t axis) const; // uniform in [0,1) per (key, slot, dimension, axis); 0.5 without jitter

    SamplerType type_ = SamplerType::Independent;
    uint32_t n_ = 1;               // samples per pixel set
    uint32_t cols_ = 1, rows_ = 1; // stratified: grid side; multijitter: n_ = cols_ × rows_; orthogonal: p
    uint64_t seed_offset_ = 0;
    bool jitter_ = true;

    PCG32 rng_;         // independent
    uint64_t key_ = 0;  // hash of (seed, pixel, set of n_ samples)
    uint32_t slot_ = 0; // the sample's index within its set
    uint32_t row_ = 0;  // orthogonal: the sample's (permuted) row of the orthogonal array
    uint32_t dim_ = 0;  // dimensions drawn since start()
};

} // namespace penumbra
