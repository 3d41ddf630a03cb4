// weft/core/rng.h — counter-based random numbers.
//
// PCG32 (O'Neill 2014) with a selectable stream, as in pbrt-v4: a path, pixel
// or sample index picks the stream and the user seed picks the offset, so
// results do not depend on how work is split across threads.
#pragma once

#include <cstdint>
#include <cstring>

namespace weft {

// 64-bit finaliser (MurmurHash3 fmix64): a good scrambler for seeds and indices.
constexpr uint64_t mixBits(uint64_t v) {
    v ^= v >> 33;
    v *= 0xff51afd7ed558ccdULL;
    v ^= v >> 33;
    v *= 0xc4ceb9fe1a85ec53ULL;
    v ^= v >> 33;
    return v;
}

inline uint64_t hashDouble(double d) {
    uint64_t bits;
    std::memcpy(&bits, &d, sizeof bits);
    return mixBits(bits);
}

class Rng {
public:
    Rng() { setSequence(0, 0); }
    // stream: which independent sequence (e.g. path index); seed: user seed.
    Rng(uint64_t stream, uint64_t seed) { setSequence(stream, seed); }

    void setSequence(uint64_t stream, uint64_t seed) {
        state_ = 0u;
        inc_ = (stream << 1u) | 1u;
        nextU32();
        state_ += mixBits(seed ^ 0x9e3779b97f4a7c15ULL);
        nextU32();
    }

    uint32_t nextU32() {
        const uint64_t old = state_;
        state_ = old * 0x5851f42d4c957f2dULL + inc_;
        const uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
        const uint32_t rot = static_cast<uint32_t>(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31));
    }

    // Uniform double in [0, 1) with 53 random bits.
    double uniform() {
        const uint64_t hi = nextU32(), lo = nextU32();
        return static_cast<double>(((hi << 32) | lo) >> 11) * 0x1.0p-53;
    }

private:
    uint64_t state_ = 0, inc_ = 1;
};

}  // namespace weft
