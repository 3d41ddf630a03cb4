// weft/core/sample_stream.h — the random numbers of one pixel sample.
//
// A path draws its numbers from a SampleStream: get1D() and get2D() in the
// order the path tracer uses them. Two kinds:
//   - independent: every number from the sample's PCG32 (core/rng.h), in
//     call order, so images are the same as drawing from the Rng directly;
//   - sobol: pbrt-v4's PaddedSobolSampler. Each request (1D or 2D) takes the
//     next pair of dimensions: a point of the first two Sobol' dimensions at
//     the pixel sample's index, the index shuffled and the point
//     Owen-scrambled by hashes of (seed, pixel, pair) (Burley 2020,
//     "Practical Hash-based Owen Scrambling"; pbrt-v4 FastOwenScrambler).
//     Samples of one pixel are then stratified in every pair (the pixel
//     area, a light sample, a BSDF direction), while each single sample is
//     still uniform and independent across pairs: the estimate stays
//     unbiased and its error falls faster than 1/spp where the integrand is
//     smooth. Requests after the first kSobolPairs come from the Rng.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include "weft/core/rng.h"

namespace weft {

enum class SamplerKind { Independent, Sobol };

// Every kind, in the order of their names in messages and scene-file checks.
inline constexpr std::array<SamplerKind, 2> kSamplerKinds = {SamplerKind::Independent,
                                                             SamplerKind::Sobol};

constexpr std::string_view samplerKindName(SamplerKind k) {
    return k == SamplerKind::Sobol ? "sobol" : "independent";
}

// The kind named `name`, or nullopt.
constexpr std::optional<SamplerKind> samplerKindFromName(std::string_view name) {
    for (const SamplerKind k : kSamplerKinds)
        if (samplerKindName(k) == name) return k;
    return std::nullopt;
}

// Bit i of v to bit 31 - i.
constexpr uint32_t reverseBits32(uint32_t v) {
    v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
    v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
    v = ((v >> 4) & 0x0F0F0F0Fu) | ((v & 0x0F0F0F0Fu) << 4);
    v = ((v >> 8) & 0x00FF00FFu) | ((v & 0x00FF00FFu) << 8);
    return (v >> 16) | (v << 16);
}

// Owen scrambling of a bit-reversed 32-bit fixed-point number by a hash:
// each bit is flipped as a function of the bits below it here, which are the
// more significant ones of the number (pbrt-v4 FastOwenScrambler without its
// two reversals).
constexpr uint32_t owenScrambleReversed(uint32_t r, uint32_t seed) {
    r ^= r * 0x3d20adeau;
    r += seed;
    r *= (seed >> 16) | 1u;
    r ^= r * 0x05526c56u;
    r ^= r * 0x53a22864u;
    return r;
}

constexpr uint32_t owenScramble(uint32_t v, uint32_t seed) {
    return reverseBits32(owenScrambleReversed(reverseBits32(v), seed));
}

// Sample indices that the sobol sampler tells apart: 2^20, the most spp a
// render takes (RenderOptions).
inline constexpr int kSobolIndexBits = 20;

// The second Sobol' dimension (primitive polynomial x + 1, direction numbers
// v_0 = 2^31, v_k = v_{k-1} ^ (v_{k-1} >> 1)) as the XOR of one table entry
// per byte of the index.
struct SobolSecondDimension {
    uint32_t byte[3][256] = {};
    constexpr SobolSecondDimension() {
        uint32_t v[24] = {};
        v[0] = 1u << 31;
        for (int k = 1; k < 24; ++k) v[k] = v[k - 1] ^ (v[k - 1] >> 1);
        for (int b = 0; b < 3; ++b)
            for (int i = 0; i < 256; ++i)
                for (int bit = 0; bit < 8; ++bit)
                    if (i >> bit & 1) byte[b][i] ^= v[8 * b + bit];
    }
    constexpr uint32_t operator()(uint32_t index) const {
        return byte[0][index & 255u] ^ byte[1][index >> 8 & 255u] ^ byte[2][index >> 16 & 255u];
    }
};
inline constexpr SobolSecondDimension kSobolSecondDimension{};

// Point `index` (< 2^24) of the first two dimensions of the Sobol' sequence,
// 32-bit fixed point: van der Corput, and the dimension above.
constexpr void sobol2D(uint32_t index, uint32_t* x, uint32_t* y) {
    *x = reverseBits32(index);
    *y = kSobolSecondDimension(index);
}

class SampleStream {
  public:
    // `pixelKey` names the pixel (and anything else that must decorrelate
    // streams, such as the user seed); `index` is the sample's number in it.
    SampleStream(SamplerKind kind, Rng& rng, uint64_t pixelKey, uint32_t index)
        : kind_(kind), rng_(rng), pixelKey_(pixelKey), indexReversed_(reverseBits32(index)) {}

    double get1D() { return usesRng() ? rng_.uniform() : sobolPair()[0]; }

    std::array<double, 2> get2D() {
        if (usesRng()) {
            const double u = rng_.uniform();
            return {u, rng_.uniform()};
        }
        return sobolPair();
    }

    // The generator for numbers whose order varies from path to path (inside
    // a BSDF's sample, for example).
    Rng& rng() { return rng_; }

    // Pairs after this many come from the Rng: stratifying a path's later
    // bounces gains little (their integrand is not smooth), and long fiber
    // paths stay as cheap as with the independent sampler.
    static constexpr int kSobolPairs = 16;

  private:
    bool usesRng() const { return kind_ == SamplerKind::Independent || pair_ >= kSobolPairs; }

    // The next pair's point: the index Owen-scrambled (shuffled) within the
    // 2^20 indices, its Sobol' point, each coordinate Owen-scrambled; three
    // hashes of (pixel key, pair).
    std::array<double, 2> sobolPair() {
        const uint64_t pair = static_cast<uint64_t>(pair_++);
        const uint64_t h = mixBits(pixelKey_ ^ mixBits(pair + 0x632be59bd9b4e019ULL));
        const uint64_t h2 = mixBits(h);
        // The van der Corput point is reverseBits32(shuffled), so its Owen
        // scrambling in reversed form starts from `shuffled` itself.
        const uint32_t shuffled =
            reverseBits32(owenScrambleReversed(indexReversed_, static_cast<uint32_t>(h))) &
            ((1u << kSobolIndexBits) - 1);
        const uint32_t x =
            reverseBits32(owenScrambleReversed(shuffled, static_cast<uint32_t>(h >> 32)));
        const uint32_t y = owenScramble(kSobolSecondDimension(shuffled), static_cast<uint32_t>(h2));
        return {toUnit(x), toUnit(y)};
    }

    // 32-bit fixed point to (0, 1): the centre of its 2^-32 interval.
    static double toUnit(uint32_t v) { return (static_cast<double>(v) + 0.5) * 0x1.0p-32; }

    SamplerKind kind_;
    Rng& rng_;
    uint64_t pixelKey_;
    uint32_t indexReversed_;  // the sample's index, bit-reversed
    int pair_ = 0;            // pairs used so far
};

}  // namespace weft
