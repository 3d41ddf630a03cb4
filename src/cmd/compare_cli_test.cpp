// End-to-end tests of `weft compare`: the JSON line and file, the heatmap PNG,
// the flags and input errors.
#include <gtest/gtest.h>
#include <stb/stb_image.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "cli_test_util.h"
#include "weft/core/file.h"
#include "weft/core/image.h"
#include "weft/core/image_io.h"

namespace weft {
namespace {

using testing::contains;
using testing::expectUserError;
using testing::RunResult;

// A smooth gradient, so that SSIM of a shifted copy is well defined.
Image gradient(int w, int h, double offset) {
    Image image(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            image.set(x, y, {0.02 * x + offset, 0.03 * y + offset, 0.01 * (x + y) + offset});
    return image;
}

class CompareCliTest : public testing::CliTestBase {
  protected:
    void SetUp() override {
        CliTestBase::SetUp();
        writeExr(path("ref.exr"), gradient(16, 12, 0.1));
        writeExr(path("same.exr"), gradient(16, 12, 0.1));
        writeExr(path("off.exr"), gradient(16, 12, 0.3));
    }
};

TEST_F(CompareCliTest, JsonFileEqualsStdout) {
    const RunResult r = run("compare off.exr ref.exr --json result.json --exposure 1");
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string file = readFile(path("result.json"));
    EXPECT_EQ(file, r.out);
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1);
    const nlohmann::json j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j.at("a"), "off.exr");
    EXPECT_EQ(j.at("b"), "ref.exr");
    EXPECT_EQ(j.at("width"), 16);
    EXPECT_EQ(j.at("height"), 12);
    EXPECT_EQ(j.at("ssim_mode"), "luminance");
    EXPECT_EQ(j.at("exposure").get<double>(), 1.0);
    // Every channel is off by 0.2 (float rounding aside): RMSE 0.2.
    EXPECT_NEAR(j.at("rmse").get<double>(), 0.2, 1e-6);
    EXPECT_GT(j.at("rel_mse").get<double>(), 0.0);
    const double ssim = j.at("ssim").get<double>();
    EXPECT_GT(ssim, 0.0);
    EXPECT_LT(ssim, 1.0);

    const RunResult pc = run("compare off.exr ref.exr --per-channel");
    ASSERT_EQ(pc.status, 0) << pc.err;
    const nlohmann::json k = nlohmann::json::parse(pc.out);
    EXPECT_EQ(k.at("ssim_mode"), "per-channel");
    EXPECT_EQ(k.at("exposure").get<double>(), 0.0);
    EXPECT_NE(k.at("ssim").get<double>(), ssim);
}

TEST_F(CompareCliTest, IdenticalImagesAndTheirHeatmap) {
    const RunResult r = run("compare same.exr ref.exr --heatmap heat.png");
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j.at("ssim").get<double>(), 1.0);
    EXPECT_EQ(j.at("rmse").get<double>(), 0.0);
    EXPECT_EQ(j.at("rel_mse").get<double>(), 0.0);
    int w = 0, h = 0, n = 0;
    const std::string png = readFile(path("heat.png"));
    unsigned char* bytes = stbi_load_from_memory(reinterpret_cast<const unsigned char*>(png.data()),
                                                 static_cast<int>(png.size()), &w, &h, &n, 3);
    ASSERT_NE(bytes, nullptr);
    EXPECT_EQ(w, 16);
    EXPECT_EQ(h, 12);
    // Every pixel is the colour scale at 1 - SSIM = 0: viridis #440154.
    for (int i = 0; i < w * h; ++i) {
        ASSERT_EQ(bytes[3 * i], 0x44) << i;
        ASSERT_EQ(bytes[3 * i + 1], 0x01) << i;
        ASSERT_EQ(bytes[3 * i + 2], 0x54) << i;
    }
    stbi_image_free(bytes);
}

TEST_F(CompareCliTest, DifferentImagesHaveABrighterHeatmap) {
    ASSERT_EQ(run("compare off.exr ref.exr --heatmap heat.png").status, 0);
    int w = 0, h = 0, n = 0;
    const std::string png = readFile(path("heat.png"));
    unsigned char* bytes = stbi_load_from_memory(reinterpret_cast<const unsigned char*>(png.data()),
                                                 static_cast<int>(png.size()), &w, &h, &n, 3);
    ASSERT_NE(bytes, nullptr);
    EXPECT_EQ(w, 16);
    EXPECT_EQ(h, 12);
    // 1 - SSIM > 0 moves along viridis towards green: more green than #440154.
    EXPECT_GT(bytes[1], 0x01);
    stbi_image_free(bytes);
}

TEST_F(CompareCliTest, ScaleAndPngInputs) {
    // One-pixel checkerboard of 0.125 and 0.375 against its mean 0.25: unlike
    // at full resolution, at --scale 2 they are the same image.
    Image checker(24, 24);
    for (int y = 0; y < 24; ++y)
        for (int x = 0; x < 24; ++x) checker.set(x, y, Rgb((x + y) % 2 ? 0.375 : 0.125));
    writeExr(path("checker.exr"), checker);
    writeExr(path("flat.exr"), testing::constantImage(24, 24, Rgb(0.25)));
    const RunResult full = run("compare checker.exr flat.exr");
    ASSERT_EQ(full.status, 0) << full.err;
    const double fullSsim = nlohmann::json::parse(full.out).at("ssim").get<double>();
    EXPECT_LT(fullSsim, 0.1);
    const RunResult coarse = run("compare checker.exr flat.exr --scale 2 --heatmap h2.png");
    ASSERT_EQ(coarse.status, 0) << coarse.err;
    const nlohmann::json c = nlohmann::json::parse(coarse.out);
    EXPECT_EQ(c.at("ssim").get<double>(), 1.0);
    EXPECT_EQ(c.at("scale"), 2);
    EXPECT_EQ(c.at("width"), 12);

    // The same images as 8-bit PNGs (a figure's panels): SSIM sees the PNG's
    // sRGB values, which round the EXR's by less than half a step.
    writePng(path("checker.png"), checker);
    writePng(path("flat.png"), testing::constantImage(24, 24, Rgb(0.25)));
    const RunResult png = run("compare checker.png flat.png");
    ASSERT_EQ(png.status, 0) << png.err;
    EXPECT_NEAR(nlohmann::json::parse(png.out).at("ssim").get<double>(), fullSsim, 0.01);
    const RunResult same = run("compare checker.png checker.png");
    ASSERT_EQ(same.status, 0) << same.err;
    EXPECT_EQ(nlohmann::json::parse(same.out).at("ssim").get<double>(), 1.0);
}

TEST_F(CompareCliTest, BadInputIsNamed) {
    writeExr(path("small.exr"), gradient(16, 10, 0.1));
    expectUserError(run("compare small.exr ref.exr --json r.json --heatmap h.png"),
                    {"small.exr", "16 x 10", "ref.exr", "16 x 12"});
    writeExr(path("tiny.exr"), gradient(8, 8, 0.1));
    expectUserError(run("compare tiny.exr tiny.exr"), {"tiny.exr", "8 x 8", "11 x 11"});
    Image nan = gradient(16, 12, 0.1);
    nan.pixels[3 * (16 * 3 + 5) + 2] = std::numeric_limits<float>::quiet_NaN();
    writeExr(path("nan.exr"), nan);
    expectUserError(run("compare ref.exr nan.exr"), {"nan.exr", "(5, 3)", "NaN"});
    expectUserError(run("compare missing.exr ref.exr"), {"missing.exr"});
    expectUserError(run("compare ref.exr ref.jpg"), {"ref.jpg", ".exr, .hdr or .png"});
    expectUserError(run("compare ref.exr gone.png"), {"gone.png"});
    expectUserError(run("compare off.exr ref.exr --scale 0"), {"--scale 0", "[1, 64]"});
    expectUserError(run("compare off.exr ref.exr --scale 2"),
                    {"off.exr", "16 x 12", "--scale 2", "22 x 22"});
    expectUserError(run("compare off.exr ref.exr --exposure 65"), {"--exposure", "[-64, 64]"});
    expectUserError(run("compare off.exr ref.exr --json nodir/r.json"), {"nodir/r.json"});
    EXPECT_EQ(run("compare off.exr").status, 2);  // the reference is required
    EXPECT_FALSE(std::filesystem::exists(path("r.json")));
    EXPECT_FALSE(std::filesystem::exists(path("h.png")));
}

TEST_F(CompareCliTest, MontageOfRendersAndAHeatmap) {
    ASSERT_EQ(run("compare off.exr ref.exr --heatmap heat.png").status, 0);
    const RunResult r = run("montage ref.exr off.exr heat.png --gap 3 --out fig.png");
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json line = nlohmann::json::parse(r.out);
    EXPECT_EQ(line.at("width"), 3 * (16 + 3) + 3);
    EXPECT_EQ(line.at("height"), 12 + 2 * 3);
    int w = 0, h = 0, n = 0;
    unsigned char* bytes = stbi_load(path("fig.png").c_str(), &w, &h, &n, 3);
    ASSERT_NE(bytes, nullptr);
    EXPECT_EQ(w, 60);
    EXPECT_EQ(bytes[0], 255);  // the white border
    stbi_image_free(bytes);
    expectUserError(run("montage ref.exr --out fig.exr"), {"--out", ".png"});
    expectUserError(run("montage ref.exr missing.exr --out f2.png"), {"missing.exr"});
    expectUserError(run("montage ref.exr --columns 99 --out f2.png"), {"--columns", "[0, 64]"});
    EXPECT_FALSE(std::filesystem::exists(path("f2.png")));
}

// Issue 41: montage drew NaN and infinite pixels black (compare refused
// them), and both read a Radiance header "-Y 4294967312 +X 4294967312" as
// 16 x 16 and a PNG whose IHDR checksum is wrong: one check where images
// enter, so both commands refuse each of them with exit 2, naming the file.
TEST_F(CompareCliTest, CompareAndMontageRefuseTheSameBadImages) {
    Image inf = gradient(16, 12, 0.1);
    inf.pixels[3 * (16 * 3 + 5) + 2] = std::numeric_limits<float>::infinity();
    writeExr(path("inf.exr"), inf);
    Image nan = gradient(16, 12, 0.1);
    nan.pixels[3 * (16 * 11 + 15)] = std::numeric_limits<float>::quiet_NaN();
    writeExr(path("nan.exr"), nan);
    writeFileAtomic(path("wrap.hdr"),
                    "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4294967312 +X 4294967312\n" +
                        std::string(16 * 16 * 4, '\x80'));
    writePng(path("heat.png"), gradient(16, 12, 0.1));
    std::string png = readFile(path("heat.png"));
    png[29] ^= 1;  // the IHDR chunk's CRC
    writeFileAtomic(path("crc.png"), png);
    const std::pair<std::string, std::vector<std::string>> bad[] = {
        {"inf.exr", {"inf.exr", "pixel (5, 3) channel B is infinite"}},
        {"nan.exr", {"nan.exr", "pixel (15, 11) channel R is NaN"}},
        {"wrap.hdr", {"wrap.hdr", "4294967312 x 4294967312"}},
        {"crc.png", {"crc.png", "IHDR", "CRC"}}};
    for (const auto& [file, parts] : bad) {
        for (const std::string& command :
             {"montage ref.exr " + file + " --out fig.png", "compare ref.exr " + file,
              "compare " + file + " ref.exr --json r.json"}) {
            const RunResult r = run(command);
            EXPECT_EQ(r.status, 2) << command << "\n" << r.out << r.err;
            for (const std::string& part : parts)
                EXPECT_TRUE(contains(r.err, part))
                    << command << ": '" << r.err << "' lacks '" << part << "'";
        }
    }
    EXPECT_FALSE(std::filesystem::exists(path("fig.png")));
    EXPECT_FALSE(std::filesystem::exists(path("r.json")));
    // The good PNG still goes into a figure.
    EXPECT_EQ(run("montage ref.exr heat.png --out fig.png").status, 0);
}

TEST_F(CompareCliTest, Help) {
    const RunResult r = run("compare --help");
    EXPECT_EQ(r.status, 0) << r.err;
    for (const char* flag : {"--heatmap", "--json", "--per-channel", "--exposure"})
        EXPECT_TRUE(contains(r.out, flag)) << flag << " missing from\n" << r.out;
}

}  // namespace
}  // namespace weft
