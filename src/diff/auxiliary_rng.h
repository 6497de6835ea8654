// The random numbers of the auxiliary samples of one camera sample (warped-area sampling's auxiliary rays,
// diff/was/warped_area.h; warped-area reparameterization's auxiliary points, diff/war/velocity_field.h): a PCG stream of
// their own per (seed, pixel, sample), so that the unbiased estimators' random sample counts do not shift the
// path sampler's dimensions (and a path is the same with and without warping).
#pragma once
#include "core/rng.h"
#include "core/vector.h"

namespace penumbra {

// Offsets that keep one estimator's streams apart from another's for the same camera sample.
struct AuxiliarySalt {
    uint64_t sample = 0, pixel = 0;
};

class AuxiliaryRng {
  public:
    AuxiliaryRng(uint64_t seed, uint64_t pixel, uint64_t sample, AuxiliarySalt salt = {})
        : pcg_(mix_bits(seed ^ mix_bits(pixel * 0x9E3779B97F4A7C15ULL + sample + salt.sample)),
               mix_bits(seed + pixel + salt.pixel)) {}
    float next_1d() { return pcg_.next_float(); }
    uint64_t next_u64() { return (uint64_t(pcg_.next_uint()) << 32) | pcg_.next_uint(); }
    Vec2f next_2d() {
        const float a = pcg_.next_float();
        return {a, pcg_.next_float()};
    }

  private:
    PCG32 pcg_;
};

} // namespace penumbra
