#include "weft/core/sample_stream.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace weft {
namespace {

// The points of one dimension pair for samples [first, first + count) of a pixel.
std::vector<std::array<double, 2>> pairPoints(uint64_t pixelKey, int pair, uint32_t first,
                                              uint32_t count) {
    Rng rng;
    std::vector<std::array<double, 2>> points;
    for (uint32_t i = first; i < first + count; ++i) {
        SampleStream stream(SamplerKind::Sobol, rng, pixelKey, i);
        for (int p = 0; p < pair; ++p) stream.get2D();
        points.push_back(stream.get2D());
    }
    return points;
}

// A (0, m, 2)-net in base 2: every elementary interval [a 2^-j, (a+1) 2^-j) x
// [b 2^-(m-j), (b+1) 2^-(m-j)) of area 2^-m holds exactly one of the 2^m points.
bool isZeroNet(const std::vector<std::array<double, 2>>& points, int m) {
    for (int j = 0; j <= m; ++j) {
        const int nx = 1 << j, ny = 1 << (m - j);
        std::vector<int> count(static_cast<size_t>(nx) * ny, 0);
        for (const auto& p : points) {
            const int x = static_cast<int>(p[0] * nx), y = static_cast<int>(p[1] * ny);
            if (x < 0 || x >= nx || y < 0 || y >= ny) return false;
            ++count[static_cast<size_t>(y) * nx + x];
        }
        for (int c : count)
            if (c != 1) return false;
    }
    return true;
}

TEST(Sobol, FirstTwoDimensionsMatchTheDirectionNumbers) {
    // Dimension 0 is the van der Corput sequence, dimension 1 has direction
    // numbers m = 1, 3, 5, 15 (Joe and Kuo's table): x_i = XOR of v_k over the
    // bits k of i, in natural (not Gray-code) order.
    const double x0[] = {0, 0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875};
    const double x1[] = {0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875};
    for (uint32_t i = 0; i < 8; ++i) {
        uint32_t x, y;
        sobol2D(i, &x, &y);
        EXPECT_EQ(x * 0x1.0p-32, x0[i]) << i;
        EXPECT_EQ(y * 0x1.0p-32, x1[i]) << i;
    }
    uint32_t x, y;
    sobol2D(8, &x, &y);  // v_3 = m_3 / 16 = 15 / 16
    EXPECT_EQ(y * 0x1.0p-32, 15.0 / 16);
}

TEST(Sobol, EveryAlignedBlockOfAPixelsSamplesIsAZeroNetInEachPair) {
    // Owen scrambling and the shuffled index keep the (0, 2)-sequence
    // property: samples [k 2^m, (k+1) 2^m) of a pixel stratify every pair.
    for (uint64_t key : {1ull, 77ull, 0x9e3779b97f4a7c15ull}) {
        for (int pair : {0, 1, 5, SampleStream::kSobolPairs - 1}) {
            for (int m = 1; m <= 8; ++m) {
                for (uint32_t block : {0u, 1u, 3u}) {
                    const uint32_t n = 1u << m;
                    EXPECT_TRUE(isZeroNet(pairPoints(key, pair, block * n, n), m))
                        << "key " << key << " pair " << pair << " m " << m << " block " << block;
                }
            }
        }
    }
}

TEST(Sobol, ScrambledPointsAreUniformAndPairsIndependentAcrossPixels) {
    // Over many pixels, one sample's numbers are uniform in [0, 1) and the
    // first coordinates of pairs 0 and 1 are independent: chi-square of a
    // 10 x 10 histogram (99 degrees of freedom; the 1e-4 tail is 155).
    constexpr int kBins = 10, kPixels = 50000;
    std::vector<int> joint(kBins * kBins, 0);
    Rng rng;
    for (int p = 0; p < kPixels; ++p) {
        SampleStream stream(SamplerKind::Sobol, rng, mixBits(static_cast<uint64_t>(p) + 1), 5);
        const double a = stream.get2D()[0];
        const double b = stream.get1D();
        ASSERT_GT(a, 0.0);
        ASSERT_LT(b, 1.0);
        ++joint[static_cast<int>(a * kBins) * kBins + static_cast<int>(b * kBins)];
    }
    const double expected = static_cast<double>(kPixels) / (kBins * kBins);
    double chi2 = 0;
    for (int c : joint) chi2 += (c - expected) * (c - expected) / expected;
    EXPECT_LT(chi2, 155.0);
}

TEST(Sobol, AreaOfADiscHasLessErrorThanIndependentSamples) {
    // The quarter disc x^2 + y^2 < 1 over the unit square (area pi / 4) from
    // 64 samples of pair 0, over 400 pixels: Owen-scrambled Sobol' points
    // have an error variance of order N^-1.5 on such an edge against N^-1
    // for independent points (about 8x less at N = 64).
    constexpr int kPixels = 400, kSpp = 64;
    double squaredError[2] = {0, 0};
    for (const SamplerKind kind : {SamplerKind::Independent, SamplerKind::Sobol}) {
        for (int p = 0; p < kPixels; ++p) {
            int inside = 0;
            for (int i = 0; i < kSpp; ++i) {
                Rng rng(static_cast<uint64_t>(p), static_cast<uint64_t>(i) + 1);
                SampleStream stream(kind, rng, mixBits(static_cast<uint64_t>(p)),
                                    static_cast<uint32_t>(i));
                const auto u = stream.get2D();
                inside += u[0] * u[0] + u[1] * u[1] < 1;
            }
            const double e = static_cast<double>(inside) / kSpp - M_PI / 4;
            squaredError[kind == SamplerKind::Sobol] += e * e / kPixels;
        }
    }
    // Independent: p (1 - p) / N = 0.00264.
    EXPECT_NEAR(squaredError[0], 0.00264, 0.0008);
    EXPECT_LT(squaredError[1], squaredError[0] / 4);
}

TEST(SampleStream, IndependentDrawsTheRngInCallOrder) {
    Rng a(3, 4), b(3, 4);
    SampleStream stream(SamplerKind::Independent, a, 0, 0);
    EXPECT_EQ(stream.get1D(), b.uniform());
    const double u = b.uniform(), v = b.uniform();
    const auto p = stream.get2D();
    EXPECT_EQ(p[0], u);
    EXPECT_EQ(p[1], v);
    EXPECT_EQ(stream.rng().uniform(), b.uniform());
}

TEST(SampleStream, SobolPairsEndAndTheRngGoesOn) {
    // After kSobolPairs requests the numbers are the sample's Rng, in call order.
    Rng a(3, 4), b(3, 4);
    SampleStream stream(SamplerKind::Sobol, a, 99, 7);
    for (int p = 0; p < SampleStream::kSobolPairs; ++p) stream.get1D();
    EXPECT_EQ(stream.get1D(), b.uniform());
    const double u = b.uniform(), v = b.uniform();
    const auto p = stream.get2D();
    EXPECT_EQ(p[0], u);
    EXPECT_EQ(p[1], v);
}

TEST(SampleStream, KindsHaveNames) {
    for (const SamplerKind k : {SamplerKind::Independent, SamplerKind::Sobol})
        EXPECT_EQ(samplerKindFromName(samplerKindName(k)), k);
    EXPECT_FALSE(samplerKindFromName("halton"));
}

}  // namespace
}  // namespace weft
