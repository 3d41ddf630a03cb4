// Tests of weft/eval/image_compare: SSIM against hand values and an
// independent brute-force SSIM, RMSE and relative MSE by hand, the heatmap and
// the input errors.
#include "weft/eval/image_compare.h"

#include <gtest/gtest.h>
#include <stb/stb_image.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "weft/core/image_io.h"
#include "weft/core/rng.h"
#include "weft/core/test_util.h"

namespace weft::eval {
namespace {

using testing::expectInputError;

using testing::constantImage;

Image randomImage(int w, int h, uint64_t seed, double maxValue) {
    Rng rng(7, seed);
    Image image(w, h);
    for (float& v : image.pixels) v = static_cast<float>(maxValue * rng.uniform());
    return image;
}

// The sRGB encoding, written out here independently of core/image.
double srgb(double v) {
    v = v < 0 ? 0 : (v > 1 ? 1 : v);
    return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

// SSIM of two constant planes: the sigma terms are (0 + C2) / (0 + C2) = 1.
double constantSsim(double muA, double muB) {
    const double c1 = 0.0001;
    return (2 * muA * muB + c1) / (muA * muA + muB * muB + c1);
}

CompareOptions options(SsimMode mode = SsimMode::Luminance, double exposure = 0) {
    CompareOptions o;
    o.mode = mode;
    o.exposure = exposure;
    return o;
}

// Brute-force SSIM, plainly: tone map each pixel, then for each window wholly
// inside the image loop over its 11 x 11 pixels with 2D Gaussian weights.
// `channel` -1: luminance; 0..2: that channel. Returns the map (valid region).
std::vector<double> bruteForceSsimMap(const Image& a, const Image& b, int channel,
                                      double exposure) {
    auto tone = [&](const Image& im, int x, int y) {
        const Rgb p = im.get(x, y);
        const double v = channel < 0 ? 0.2126 * p.r + 0.7152 * p.g + 0.0722 * p.b : p[channel];
        return srgb(v * std::pow(2.0, exposure));
    };
    double weights[11][11], total = 0;
    for (int j = 0; j < 11; ++j)
        for (int i = 0; i < 11; ++i) {
            const double dx = i - 5, dy = j - 5;
            weights[j][i] = std::exp(-(dx * dx + dy * dy) / (2 * 1.5 * 1.5));
            total += weights[j][i];
        }
    std::vector<double> map;
    for (int cy = 5; cy < a.height - 5; ++cy)
        for (int cx = 5; cx < a.width - 5; ++cx) {
            double muA = 0, muB = 0;
            for (int j = 0; j < 11; ++j)
                for (int i = 0; i < 11; ++i) {
                    const double w = weights[j][i] / total;
                    muA += w * tone(a, cx - 5 + i, cy - 5 + j);
                    muB += w * tone(b, cx - 5 + i, cy - 5 + j);
                }
            double varA = 0, varB = 0, cov = 0;
            for (int j = 0; j < 11; ++j)
                for (int i = 0; i < 11; ++i) {
                    const double w = weights[j][i] / total;
                    const double da = tone(a, cx - 5 + i, cy - 5 + j) - muA;
                    const double db = tone(b, cx - 5 + i, cy - 5 + j) - muB;
                    varA += w * da * da;
                    varB += w * db * db;
                    cov += w * da * db;
                }
            const double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;
            map.push_back((2 * muA * muB + c1) * (2 * cov + c2) /
                          ((muA * muA + muB * muB + c1) * (varA + varB + c2)));
        }
    return map;
}

TEST(ImageCompare, IdenticalImagesScoreExactlyOne) {
    // Values up to 2 so that some clip in the tone map.
    const Image a = randomImage(23, 17, 1, 2.0);
    for (SsimMode mode : {SsimMode::Luminance, SsimMode::PerChannel}) {
        const ImageComparison c = compareImages(a, "a.exr", a, "b.exr", options(mode, 0.7));
        EXPECT_EQ(c.ssim, 1.0);
        EXPECT_EQ(c.rmse, 0.0);
        EXPECT_EQ(c.relMse, 0.0);
        ASSERT_EQ(c.ssimMap.width, 13);
        ASSERT_EQ(c.ssimMap.height, 7);
        for (double v : c.ssimMap.values) EXPECT_EQ(v, 1.0);
    }
}

TEST(ImageCompare, ConstantImagesMatchTheLuminanceTerm) {
    // Values exact in float, so that the hand value sees what the image holds.
    const ImageComparison c = compareImages(constantImage(14, 12, Rgb(0.25)), "a.exr",
                                            constantImage(14, 12, Rgb(0.0625)), "b.exr", options());
    const double expected = constantSsim(1.055 * std::pow(0.25, 1 / 2.4) - 0.055,
                                         1.055 * std::pow(0.0625, 1 / 2.4) - 0.055);
    EXPECT_LT(expected, 0.95);
    EXPECT_NEAR(c.ssim, expected, 1e-12);
    ASSERT_EQ(c.ssimMap.values.size(), 4u * 2u);
    for (double v : c.ssimMap.values) EXPECT_NEAR(v, expected, 1e-12);

    // Two stops of exposure make 0.0625 and 0.015625 the same pair.
    const ImageComparison e = compareImages(constantImage(14, 12, Rgb(0.0625)), "a.exr",
                                            constantImage(14, 12, Rgb(0.015625)), "b.exr",
                                            options(SsimMode::Luminance, 2));
    EXPECT_NEAR(e.ssim, expected, 1e-12);
    EXPECT_EQ(e.exposure, 2);

    // Black against white: C1 / (1 + C1).
    const ImageComparison bw = compareImages(constantImage(11, 11, Rgb(0)), "a.exr",
                                             constantImage(11, 11, Rgb(1)), "b.exr", options());
    EXPECT_NEAR(bw.ssim, 1e-4 / (1 + 1e-4), 1e-15);
    ASSERT_EQ(bw.ssimMap.values.size(), 1u);

    // Above 1 after exposure both clamp to white: the same tone-mapped image.
    const ImageComparison clipped = compareImages(
        constantImage(11, 11, Rgb(3)), "a.exr", constantImage(11, 11, Rgb(1)), "b.exr", options());
    EXPECT_NEAR(clipped.ssim, 1.0, 1e-15);
    EXPECT_GT(clipped.rmse, 1.9);
}

TEST(ImageCompare, KnownOffsetOnARamp) {
    // b = a + d on a linear ramp: the Gaussian mean of a window is its centre
    // value, and both variances equal the covariance, so the contrast-structure
    // term is 1 and SSIM = (2 mu (mu + d) + C1) / (mu^2 + (mu + d)^2 + C1).
    const double d = 0.1;
    Plane a(15, 13), b(15, 13);
    auto ramp = [](int x, int y) { return 0.2 + 0.01 * x + 0.005 * y; };
    for (int y = 0; y < 13; ++y)
        for (int x = 0; x < 15; ++x) a.at(x, y) = ramp(x, y), b.at(x, y) = ramp(x, y) + d;
    const Plane map = ssimMap(a, b);
    ASSERT_EQ(map.width, 5);
    ASSERT_EQ(map.height, 3);
    for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 5; ++x) {
            const double mu = ramp(x + 5, y + 5);
            EXPECT_NEAR(map.at(x, y), constantSsim(mu, mu + d), 1e-12) << x << ", " << y;
        }
}

TEST(ImageCompare, MatchesBruteForceSsim) {
    // A random reference and a noisy copy: SSIM well inside (0, 1).
    const Image b = randomImage(19, 16, 2, 1.5);
    Image a = b;
    Rng rng(3, 4);
    for (float& v : a.pixels)
        v = static_cast<float>(std::max(0.0, v + 1.2 * (rng.uniform() - 0.5)));
    const double exposure = -0.5;
    for (SsimMode mode : {SsimMode::Luminance, SsimMode::PerChannel}) {
        const ImageComparison c = compareImages(a, "a.exr", b, "b.exr", options(mode, exposure));
        std::vector<double> expected = bruteForceSsimMap(a, b, -1, exposure);
        if (mode == SsimMode::PerChannel) {
            // Per channel: the map is the average of the three channels' maps.
            expected.assign(expected.size(), 0.0);
            for (int k = 0; k < 3; ++k) {
                const std::vector<double> m = bruteForceSsimMap(a, b, k, exposure);
                for (size_t i = 0; i < m.size(); ++i) expected[i] += m[i] / 3;
            }
        }
        ASSERT_EQ(expected.size(), 9u * 6u);
        ASSERT_EQ(c.ssimMap.values.size(), expected.size());
        double meanExpected = 0;
        for (size_t i = 0; i < expected.size(); ++i) {
            EXPECT_NEAR(c.ssimMap.values[i], expected[i], 1e-9) << i;
            meanExpected += expected[i] / static_cast<double>(expected.size());
        }
        EXPECT_NEAR(c.ssim, meanExpected, 1e-9);
        EXPECT_GT(c.ssim, 0.1);
        EXPECT_LT(c.ssim, 0.95);
    }
}

TEST(ImageCompare, SsimIsSymmetric) {
    const Image a = randomImage(16, 14, 5, 1.0), b = randomImage(16, 14, 6, 1.0);
    for (SsimMode mode : {SsimMode::Luminance, SsimMode::PerChannel}) {
        const ImageComparison ab = compareImages(a, "a.exr", b, "b.exr", options(mode));
        const ImageComparison ba = compareImages(b, "b.exr", a, "a.exr", options(mode));
        EXPECT_EQ(ab.ssim, ba.ssim);
        EXPECT_EQ(ab.ssimMap.values, ba.ssimMap.values);
        EXPECT_EQ(ab.rmse, ba.rmse);
        EXPECT_LT(ab.ssim, 0.5);  // unrelated noise
    }
}

TEST(ImageCompare, RmseAndRelativeMseByHand) {
    // 12 x 12 grey 0.5 reference; one pixel off by (+1, 0, -0.5), one black
    // reference pixel where the image has 0.125 in every channel: 432 values.
    Image b = constantImage(12, 12, Rgb(0.5));
    Image a = b;
    a.set(3, 4, {1.5, 0.5, 0.0});
    b.set(10, 1, Rgb(0));
    a.set(10, 1, Rgb(0.125));
    const ImageComparison c = compareImages(a, "a.exr", b, "b.exr", options());
    const double squares = 1.0 + 0.25 + 3 * 0.015625;
    EXPECT_NEAR(c.rmse, std::sqrt(squares / 432), 1e-12);
    const double relative = (1.0 + 0.25) / (0.25 + 0.01) + 3 * 0.015625 / (0 + 0.01);
    EXPECT_NEAR(c.relMse, relative / 432, 1e-12);
    // b is the reference: swapping the roles changes the relative MSE.
    EXPECT_NEAR(relativeMse(b, a),
                (1.0 / (2.25 + 0.01) + 0.25 / 0.01 + 3 * 0.015625 / (0.015625 + 0.01)) / 432,
                1e-12);
    EXPECT_DOUBLE_EQ(rmse(b, a), c.rmse);
}

TEST(ImageCompare, PerChannelModeAveragesTheChannels) {
    // Constant images equal in R and B, different in G.
    const Image a = constantImage(12, 13, {0.25, 0.5, 0.0625});
    const Image b = constantImage(12, 13, {0.25, 0.0625, 0.0625});
    const ImageComparison c = compareImages(a, "a.exr", b, "b.exr", options(SsimMode::PerChannel));
    const double g = constantSsim(srgb(0.5), srgb(0.0625));
    EXPECT_NEAR(c.ssim, (1 + g + 1) / 3, 1e-12);
    EXPECT_EQ(toJson(c).at("ssim_mode"), "per-channel");
    // Luminance mode sees only Y.
    const ImageComparison l = compareImages(a, "a.exr", b, "b.exr", options());
    EXPECT_NEAR(l.ssim,
                constantSsim(srgb(0.2126 * 0.25 + 0.7152 * 0.5 + 0.0722 * 0.0625),
                             srgb(0.2126 * 0.25 + 0.7152 * 0.0625 + 0.0722 * 0.0625)),
                1e-12);
    EXPECT_EQ(toJson(l).at("ssim_mode"), "luminance");
}

TEST(ImageCompare, JsonHasEveryField) {
    const ImageComparison c =
        compareImages(constantImage(12, 11, Rgb(0.2)), "x.exr", constantImage(12, 11, Rgb(0.1)),
                      "ref.exr", options(SsimMode::Luminance, 1.5));
    const nlohmann::json j = toJson(c);
    EXPECT_EQ(j.size(), 13u);
    EXPECT_EQ(j.at("a"), "x.exr");
    EXPECT_EQ(j.at("b"), "ref.exr");
    EXPECT_EQ(j.at("width"), 12);
    EXPECT_EQ(j.at("height"), 11);
    EXPECT_EQ(j.at("ssim").get<double>(), c.ssim);
    EXPECT_EQ(j.at("rmse").get<double>(), c.rmse);
    EXPECT_EQ(j.at("rel_mse").get<double>(), c.relMse);
    EXPECT_EQ(j.at("exposure").get<double>(), 1.5);
    EXPECT_EQ(j.at("scale"), 1);
    for (int channel = 0; channel < 3; ++channel) {
        EXPECT_NEAR(j.at("mean_a")[channel].get<double>(), 0.2, 1e-7);
        EXPECT_NEAR(j.at("mean_b")[channel].get<double>(), 0.1, 1e-7);
        EXPECT_NEAR(j.at("mean_ratio")[channel].get<double>(), 2.0, 1e-6);
    }
}

TEST(ImageCompare, ChannelMeansByHandAndTheirRatio) {
    // 24 x 24 reference (0.5, 0.25, 0); the image is the reference with one
    // pixel raised by (5.76, 0, 0) and one G value halved: means by hand.
    const Image b = constantImage(24, 24, {0.5, 0.25, 0.0});
    Image a = b;
    a.set(2, 3, {6.26, 0.25, 0.0});
    a.set(7, 7, {0.5, 0.125, 0.0});
    const ImageComparison c = compareImages(a, "a.exr", b, "b.exr", options());
    EXPECT_NEAR(c.meanA.r, 0.5 + 5.76 / 576, 1e-7);
    EXPECT_NEAR(c.meanA.g, 0.25 - 0.125 / 576, 1e-7);
    EXPECT_EQ(c.meanA.b, 0.0);
    EXPECT_NEAR(c.meanB.r, 0.5, 1e-7);
    const nlohmann::json ratio = toJson(c).at("mean_ratio");
    EXPECT_NEAR(ratio[0].get<double>(), 1.02, 1e-6);
    EXPECT_NEAR(ratio[1].get<double>(), 1 - 0.5 / 576, 1e-6);
    EXPECT_TRUE(ratio[2].is_null());  // a black reference channel has no ratio
    // With --scale the means are those of the block averages: the same numbers.
    CompareOptions blocks = options();
    blocks.scale = 2;
    const ImageComparison s = compareImages(a, "a.exr", b, "b.exr", blocks);
    EXPECT_NEAR(s.meanA.r, c.meanA.r, 1e-7);
    EXPECT_NEAR(s.meanA.g, c.meanA.g, 1e-7);
}

TEST(ImageCompare, BoxDownsampledAveragesBlocksByHand) {
    // Pixel (x, y) holds (x + 10 y, 2 x, 1): a 5 x 4 image gives 2 x 2 blocks,
    // the fifth column dropped.
    Image image(5, 4);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 5; ++x) image.set(x, y, {x + 10.0 * y, 2.0 * x, 1});
    const Image down = boxDownsampled(image, 2);
    ASSERT_EQ(down.width, 2);
    ASSERT_EQ(down.height, 2);
    // Block (1, 0) covers x 2..3, y 0..1: (2 + 3 + 12 + 13) / 4, (4 + 6) / 2.
    EXPECT_EQ(down.get(1, 0).r, 7.5);
    EXPECT_EQ(down.get(1, 0).g, 5.0);
    EXPECT_EQ(down.get(1, 0).b, 1.0);
    // Block (0, 1) covers x 0..1, y 2..3: (20 + 21 + 30 + 31) / 4.
    EXPECT_EQ(down.get(0, 1).r, 25.5);
    EXPECT_EQ(boxDownsampled(image, 1).pixels, image.pixels);
    EXPECT_THROW(boxDownsampled(image, 0), std::invalid_argument);
    EXPECT_THROW(boxDownsampled(image, 5), std::invalid_argument);
}

TEST(ImageCompare, ScaleComparesStructureLargerThanTheBlock) {
    // A checkerboard of 0.125 and 0.375 (one-pixel squares) against its mean
    // 0.25: at full resolution the structure term is 0 (the flat image has no
    // variance), at scale 2 every block of the checkerboard averages to 0.25
    // exactly and the two images are the same.
    Image checker(36, 35);
    for (int y = 0; y < 35; ++y)
        for (int x = 0; x < 36; ++x) checker.set(x, y, Rgb((x + y) % 2 ? 0.375 : 0.125));
    const Image flat = constantImage(36, 35, Rgb(0.25));
    const ImageComparison full = compareImages(checker, "a.exr", flat, "b.exr", options());
    EXPECT_LT(full.ssim, 0.1);
    CompareOptions o = options();
    o.scale = 2;
    const ImageComparison coarse = compareImages(checker, "a.exr", flat, "b.exr", o);
    EXPECT_EQ(coarse.ssim, 1.0);
    EXPECT_EQ(coarse.rmse, 0.0);
    EXPECT_EQ(coarse.width, 18);
    EXPECT_EQ(coarse.height, 17);
    EXPECT_EQ(coarse.scale, 2);
    EXPECT_EQ(toJson(coarse).at("scale"), 2);
    // At scale 3 the blocks hold five of one value and four of the other
    // (alternating), so structure remains: the SSIM equals that of the
    // downsampled images compared at full resolution.
    o.scale = 3;
    const ImageComparison three = compareImages(checker, "a.exr", flat, "b.exr", o);
    EXPECT_LT(three.ssim, 0.99);
    EXPECT_EQ(three.ssim, compareImages(boxDownsampled(checker, 3), "a.exr",
                                        boxDownsampled(flat, 3), "b.exr", options())
                              .ssim);
}

TEST(ImageCompare, HeatmapColourScale) {
    auto expectColor = [](double t, double r, double g, double b) {
        const Rgb c = heatmapColorSrgb(t);
        EXPECT_NEAR(c.r * 255, r, 1e-9) << t;
        EXPECT_NEAR(c.g * 255, g, 1e-9) << t;
        EXPECT_NEAR(c.b * 255, b, 1e-9) << t;
    };
    expectColor(0, 0x44, 0x01, 0x54);
    expectColor(-3, 0x44, 0x01, 0x54);
    expectColor(0.5, 0x21, 0x90, 0x8c);
    expectColor(1, 0xfd, 0xe7, 0x25);
    expectColor(7, 0xfd, 0xe7, 0x25);
    // Halfway between the first two control points (t = 0 and 1/8).
    expectColor(1.0 / 16, (0x44 + 0x47) / 2.0, (0x01 + 0x2d) / 2.0, (0x54 + 0x7b) / 2.0);
}

TEST(ImageCompare, HeatmapOfAPerfectMatchIsTheColourAtZero) {
    const Image a = randomImage(13, 12, 8, 1.0);
    const Image heat = ssimHeatmap(compareImages(a, "a.exr", a, "b.exr", options()));
    ASSERT_EQ(heat.width, 13);
    ASSERT_EQ(heat.height, 12);
    const Rgb zero = heatmapColorSrgb(0);
    for (int y = 0; y < 12; ++y)
        for (int x = 0; x < 13; ++x) {
            const Rgb p = heat.get(x, y);
            EXPECT_NEAR(p.r, srgbToLinear(zero.r), 1e-7);
            EXPECT_NEAR(p.g, srgbToLinear(zero.g), 1e-7);
            EXPECT_NEAR(p.b, srgbToLinear(zero.b), 1e-7);
        }
    // Through the PNG encoder: the 8-bit sRGB bytes of viridis(0), #440154.
    const std::string png = encodePng(heat);
    int w = 0, h = 0, n = 0;
    unsigned char* bytes = stbi_load_from_memory(reinterpret_cast<const unsigned char*>(png.data()),
                                                 static_cast<int>(png.size()), &w, &h, &n, 3);
    ASSERT_NE(bytes, nullptr);
    EXPECT_EQ(w, 13);
    EXPECT_EQ(h, 12);
    for (int i = 0; i < w * h; ++i) {
        EXPECT_EQ(bytes[3 * i], 0x44);
        EXPECT_EQ(bytes[3 * i + 1], 0x01);
        EXPECT_EQ(bytes[3 * i + 2], 0x54);
    }
    stbi_image_free(bytes);
}

TEST(ImageCompare, HeatmapBordersCopyTheNearestValidPixel) {
    const Image b = randomImage(17, 15, 9, 1.0), a = randomImage(17, 15, 10, 1.0);
    const ImageComparison c = compareImages(a, "a.exr", b, "b.exr", options());
    const Image heat = ssimHeatmap(c);
    auto expectPixel = [&](int x, int y, int mx, int my) {
        const Rgb want = heatmapColorSrgb(1 - c.ssimMap.at(mx, my));
        const Rgb got = heat.get(x, y);
        EXPECT_NEAR(got.r, srgbToLinear(want.r), 1e-6) << x << ", " << y;
        EXPECT_NEAR(got.g, srgbToLinear(want.g), 1e-6) << x << ", " << y;
        EXPECT_NEAR(got.b, srgbToLinear(want.b), 1e-6) << x << ", " << y;
    };
    expectPixel(5, 5, 0, 0);    // first valid pixel
    expectPixel(0, 0, 0, 0);    // corner: nearest valid is (5, 5)
    expectPixel(16, 14, 6, 4);  // far corner: (11, 9)
    expectPixel(8, 0, 3, 0);    // top edge: same column, first valid row
    expectPixel(2, 9, 0, 4);    // left edge
    expectPixel(11, 9, 6, 4);   // last valid pixel
    expectPixel(7, 14, 2, 4);   // bottom edge
    // The map varies, so the checks above are not vacuous.
    EXPECT_NE(c.ssimMap.at(0, 0), c.ssimMap.at(6, 4));
}

class ImageCompareFiles : public testing::TempDirTest {};

TEST_F(ImageCompareFiles, ReadsExrFiles) {
    const Image a = randomImage(12, 12, 11, 1.0), b = randomImage(12, 12, 12, 1.0);
    writeExr(path("a.exr"), a);
    writeExr(path("b.exr"), b);
    const ImageComparison c = compareImageFiles(path("a.exr"), path("b.exr"), options());
    EXPECT_EQ(c.a, path("a.exr"));
    EXPECT_EQ(c.b, path("b.exr"));
    EXPECT_EQ(c.ssim, compareImages(a, "a", b, "b", options()).ssim);
}

TEST_F(ImageCompareFiles, ErrorsNameTheFile) {
    writeExr(path("a.exr"), randomImage(12, 12, 13, 1.0));
    writeExr(path("wide.exr"), randomImage(14, 12, 14, 1.0));
    writeExr(path("tiny.exr"), randomImage(10, 12, 15, 1.0));
    writeExr(path("tiny2.exr"), randomImage(10, 12, 16, 1.0));
    Image nan = randomImage(12, 12, 17, 1.0);
    nan.pixels[3 * (12 * 7 + 4) + 1] = std::numeric_limits<float>::quiet_NaN();
    writeExr(path("nan.exr"), nan);
    Image inf = randomImage(12, 12, 18, 1.0);
    inf.pixels[3 * (12 * 2 + 9)] = std::numeric_limits<float>::infinity();
    writeExr(path("inf.exr"), inf);

    expectInputError([&] { compareImageFiles(path("a.exr"), path("wide.exr"), options()); },
                     {"a.exr", "12 x 12", "wide.exr", "14 x 12"});
    expectInputError([&] { compareImageFiles(path("tiny.exr"), path("tiny2.exr"), options()); },
                     {"tiny.exr", "tiny2.exr", "10 x 12", "11 x 11"});
    expectInputError([&] { compareImageFiles(path("nan.exr"), path("a.exr"), options()); },
                     {"nan.exr", "(4, 7)", "G", "NaN"});
    expectInputError([&] { compareImageFiles(path("a.exr"), path("inf.exr"), options()); },
                     {"inf.exr", "(9, 2)", "R", "infinite"});
    expectInputError([&] { compareImageFiles(path("missing.exr"), path("a.exr"), options()); },
                     {"missing.exr"});
    expectInputError([&] { compareImageFiles(path("a.exr"), path("gone.hdr"), options()); },
                     {"gone.hdr"});
    for (double e : {100.0, std::numeric_limits<double>::quiet_NaN()})
        expectInputError(
            [&] {
                compareImageFiles(path("a.exr"), path("a.exr"), options(SsimMode::Luminance, e));
            },
            {"--exposure", "[-64, 64]"});
    for (int scale : {0, 65}) {
        CompareOptions o = options();
        o.scale = scale;
        expectInputError([&] { compareImageFiles(path("a.exr"), path("a.exr"), o); },
                         {"--scale " + std::to_string(scale), "[1, 64]"});
    }
    CompareOptions two = options();
    two.scale = 2;
    expectInputError([&] { compareImageFiles(path("a.exr"), path("a.exr"), two); },
                     {"a.exr", "12 x 12", "--scale 2", "22 x 22"});
}

TEST(ImageCompare, PlaneLevelMisuseIsABug) {
    EXPECT_THROW(ssimMap(Plane(12, 12), Plane(12, 11)), std::invalid_argument);
    EXPECT_THROW(ssimMap(Plane(10, 12), Plane(10, 12)), std::invalid_argument);
    EXPECT_THROW(toneMappedChannel(Image(11, 11), 3, 0), std::invalid_argument);
}

}  // namespace
}  // namespace weft::eval
