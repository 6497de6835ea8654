// PCG32 random number generator (O'Neill 2014) with independent streams.
#pragma once
#include <cstdint>

namespace penumbra {

class PCG32 {
public:
    PCG32(uint64_t state = 0x853c49e6748fea9bULL, uint64_t stream = 0xda3e39cb94b95bdbULL) { seed(state, stream); }
    void seed(uint64_t init_state, uint64_t init_seq) {
        state_ = 0u;
        inc_ = (init_seq << 1u) | 1u;
        next_uint();
        state_ += init_state;
        next_uint();
    }
    uint32_t next_uint() {
        const uint64_t old = state_;
        state_ = old * 0x5851f42d4c957f2dULL + inc_;
        const uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
        const uint32_t rot = uint32_t(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31));
    }
    // Uniform float in [0, 1).
    float next_float() {
        const uint32_t bits = (next_uint() >> 9) | 0x3f800000u;
        float f;
        static_assert(sizeof(f) == sizeof(bits));
        __builtin_memcpy(&f, &bits, sizeof(f));
        return f - 1.f;
    }

private:
    uint64_t state_ = 0, inc_ = 0;
};

// 64-bit mix (splitmix64 finalizer) used to derive per-pixel, per-sample seeds.
inline uint64_t mix_bits(uint64_t v) {
    v ^= v >> 31;
    v *= 0x7fb5d329728ea185ULL;
    v ^= v >> 27;
    v *= 0x81dadef4bc2dd44dULL;
    v ^= v >> 33;
    return v;
}

} // namespace penumbra
