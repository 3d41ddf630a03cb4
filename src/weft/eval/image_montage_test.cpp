// Tests of the figure montage: cell layout and background by hand, PNG inputs
// kept to the 8-bit value, exposure on linear inputs only, input errors.
#include "weft/eval/image_montage.h"

#include <gtest/gtest.h>
#include <stb/stb_image.h>

#include <cmath>
#include <string>
#include <vector>

#include "weft/core/file.h"
#include "weft/core/image_io.h"
#include "weft/core/test_util.h"

namespace weft::eval {
namespace {

using testing::expectInputError;

using testing::constantImage;

TEST(Montage, CellsAreCentredWithGapsOfBackground) {
    MontageOptions o;
    o.gap = 2;
    o.columns = 2;
    o.background = {0.5, 0.5, 0.5};
    // Three images in rows of two: cells are 4 x 3 (the largest width, height).
    const std::vector<Image> images = {constantImage(4, 3, {1, 0, 0}),
                                       constantImage(2, 1, {0, 1, 0}),
                                       constantImage(3, 3, {0, 0, 1})};
    const Image fig = montage(images, {true, true, true}, o);
    ASSERT_EQ(fig.width, 2 * (4 + 2) + 2);
    ASSERT_EQ(fig.height, 2 * (3 + 2) + 2);
    const auto expectColour = [&](int x, int y, const Rgb& c) {
        const Rgb v = fig.get(x, y);
        EXPECT_EQ(v.r, c.r) << x << "," << y;
        EXPECT_EQ(v.g, c.g) << x << "," << y;
        EXPECT_EQ(v.b, c.b) << x << "," << y;
    };
    expectColour(0, 0, o.background);
    expectColour(2, 2, {1, 0, 0});  // first cell starts at (gap, gap)
    expectColour(5, 4, {1, 0, 0});
    expectColour(6, 2, o.background);  // the gap after the first cell
    // Second image 2 x 1, centred in the cell at x = 8: offset (1, 1).
    expectColour(8, 3, o.background);
    expectColour(9, 3, {0, 1, 0});
    expectColour(10, 3, {0, 1, 0});
    expectColour(11, 3, o.background);
    // Third image on the second row: cell at y = 2 + 3 + 2 = 7, 3 x 3 centred at x offset 0.
    expectColour(2, 7, {0, 0, 1});
    expectColour(4, 9, {0, 0, 1});
    expectColour(5, 9, o.background);
    // The empty fourth cell is background.
    expectColour(10, 8, o.background);
}

TEST(Montage, ExposureScalesLinearInputsOnly) {
    MontageOptions o;
    o.gap = 0;
    o.exposure = 1;
    const Image fig =
        montage({constantImage(1, 1, {0.25, 0.25, 0.25}), constantImage(1, 1, {0.25, 0.25, 0.25})},
                {true, false}, o);
    EXPECT_DOUBLE_EQ(fig.get(0, 0).r, 0.5);
    EXPECT_DOUBLE_EQ(fig.get(1, 0).r, 0.25);
}

class MontageFiles : public testing::TempDirTest {};

TEST_F(MontageFiles, PngInputsKeepTheirEightBitValues) {
    // Every 8-bit value once, written by writePng and placed in a montage: the
    // montage's PNG has the same bytes per pixel.
    Image ramp(256, 1);
    for (int x = 0; x < 256; ++x) {
        const double v = srgbToLinear(x / 255.0);
        ramp.set(x, 0, {v, v, v});
    }
    writePng(path("ramp.png"), ramp);
    const Image back = readImageOrPng(path("ramp.png"));
    MontageOptions o;
    o.gap = 0;
    writePng(path("fig.png"), montage({back}, {false}, o));
    int w = 0, h = 0, n = 0;
    unsigned char* data = stbi_load(path("fig.png").c_str(), &w, &h, &n, 3);
    ASSERT_NE(data, nullptr);
    ASSERT_EQ(w, 256);
    for (int x = 0; x < 256; ++x) EXPECT_EQ(data[3 * x], x);
    stbi_image_free(data);
}

TEST_F(MontageFiles, ExrInputsAreReadAsStored) {
    writeExr(path("a.exr"), constantImage(2, 2, {0.1, 0.2, 0.3}));
    const Image im = readImageOrPng(path("a.exr"));
    EXPECT_FLOAT_EQ(static_cast<float>(im.get(1, 1).g), 0.2f);
}

TEST_F(MontageFiles, BadInputsNameTheFileOrFlag) {
    writeFileAtomic(path("bad.png"), "not a png");
    expectInputError([&] { readImageOrPng(path("bad.png")); }, {"bad.png"});
    expectInputError([&] { readImageOrPng(path("missing.exr")); }, {"missing.exr"});
    expectInputError([&] { montage({}, {}, MontageOptions{}); }, {"no images"});
    MontageOptions o;
    o.columns = -1;
    expectInputError([&] { o.validate(); }, {"--columns", "[0, 64]"});
    o = {};
    o.gap = 1000;
    expectInputError([&] { o.validate(); }, {"--gap", "[0, 256]"});
    o = {};
    o.exposure = std::nan("");
    expectInputError([&] { o.validate(); }, {"--exposure"});
    expectInputError(
        [&] {
            montage(std::vector<Image>(65, constantImage(1, 1, {})), std::vector<bool>(65, true),
                    MontageOptions{});
        },
        {"at most 64"});
}

// A chunk length that stb would reserve (1.9 GB) before reading: the libFuzzer
// finding of issue 18 (tests/data/fuzz/); and a header claiming more texels
// than the memory budget allows.
TEST_F(MontageFiles, PngHeadersClaimingHugeAllocationsAreInputErrors) {
    const std::string finding =
        readFile(std::string(WEFT_SOURCE_DIR) + "/tests/data/fuzz/png-chunk-oom.png");
    expectInputError([&] { decodePng(finding, "finding.png"); },
                     {"cannot read PNG image 'finding.png'", "claims", "truncated or corrupt"});
    expectInputError([&] { decodePng("GIF89a", "g.png"); }, {"g.png", "not a PNG file"});
}

}  // namespace
}  // namespace weft::eval
