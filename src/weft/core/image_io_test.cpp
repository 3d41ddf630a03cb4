// Tests for weft/core/image_io.h: OpenEXR and Radiance files read back bit
// for bit, their variants, and every missing, truncated or corrupt file an
// InputError naming it.
#include "weft/core/image_io.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/rng.h"
#include "weft/core/test_util.h"

namespace weft {
namespace {

using testing::expectInputError;
using testing::scaled;

using ImageFiles = testing::TempDirTest;

std::vector<std::string> filesIn(const std::filesystem::path& dir) {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(dir))
        names.push_back(e.path().filename().string());
    return names;
}

bool sameBits(const Image& a, const Image& b) {
    return a.width == b.width && a.height == b.height && a.pixels.size() == b.pixels.size() &&
           std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) == 0;
}

// Writes an EXR file with the given channels (each a w x h float or half
// plane over the data window at origin) through OpenEXR directly.
void writeExrChannels(const std::string& path, int w, int h, Imath::V2i origin,
                      const std::vector<std::pair<std::string, std::vector<float>>>& planes,
                      Imf::PixelType type) {
    Imf::Header header(Imath::Box2i(origin, origin + Imath::V2i(w - 1, h - 1)),
                       Imath::Box2i(origin, origin + Imath::V2i(w - 1, h - 1)));
    std::vector<std::vector<Imath::half>> halves;
    halves.reserve(planes.size());  // the slices point into it
    Imf::FrameBuffer fb;
    for (const auto& [name, plane] : planes) header.channels().insert(name, Imf::Channel(type));
    for (const auto& [name, plane] : planes) {
        if (type == Imf::HALF) {
            halves.emplace_back(plane.begin(), plane.end());
            fb.insert(name, Imf::Slice::Make(Imf::HALF, halves.back().data(), header.dataWindow(),
                                             sizeof(Imath::half), sizeof(Imath::half) * w));
        } else {
            fb.insert(name, Imf::Slice::Make(Imf::FLOAT, plane.data(), header.dataWindow(),
                                             sizeof(float), sizeof(float) * w));
        }
    }
    Imf::OutputFile file(path.c_str(), header);
    file.setFrameBuffer(fb);
    file.writePixels(h);
}

// --exposure auto: the 99th percentile of the luminance maps to 0.9.
TEST(AutoExposure, MapsThe99thPercentileLuminanceTo0point9) {
    Image image(10, 10);
    for (int i = 0; i < 100; ++i) image.set(i % 10, i / 10, Rgb(0.01 * (i + 1)));  // 0.01 .. 1
    // The 99th of 100 sorted values (index 99 * 0.99 -> 99) is 1.0; scaled by 8, 8.0.
    EXPECT_NEAR(autoExposure(image), std::log2(0.9 / 1.0), 1e-12);
    for (float& v : image.pixels) v *= 8;
    EXPECT_NEAR(autoExposure(image), std::log2(0.9 / 8.0), 1e-12);
    EXPECT_EQ(autoExposure(Image(4, 4)), 0.0);  // black: no change
    Image dim(1, 1);
    dim.set(0, 0, Rgb(1e-30));
    EXPECT_EQ(autoExposure(dim), 64.0);  // clamped
}

TEST_F(ImageFiles, ExrRoundTripIsBitExact) {
    Image image(5, 3);
    // Finite values only: a NaN or infinite pixel is refused where images
    // enter (NonFinitePixelsAreRefusedWhereImagesEnter).
    const float values[] = {0.0f,  1.0f,     0.1f,  3.2e38f, 1e-40f /* denormal */,
                            -2.5f, 65504.5f, 1e-7f, -0.0f,   -3.2e38f};
    for (size_t i = 0; i < image.pixels.size(); ++i) {
        image.pixels[i] = values[i % 10] * (1.0f + 0.001f * static_cast<float>(i));
        ASSERT_TRUE(std::isfinite(image.pixels[i])) << i;
    }
    const std::string path = this->path("round.exr");
    writeExr(path, image);
    EXPECT_EQ(filesIn(dir_), std::vector<std::string>{"round.exr"});  // no temp files left
    EXPECT_TRUE(sameBits(readImage(path), image));
    // Overwrites atomically, and the extension is case-insensitive.
    image.set(0, 0, Rgb(7, 8, 9));
    writeExr(path, image);
    EXPECT_TRUE(sameBits(readImage(path), image));
    std::filesystem::rename(path, this->path("ROUND.EXR"));
    EXPECT_TRUE(sameBits(readImage(this->path("ROUND.EXR")), image));
}

TEST_F(ImageFiles, ExrVariantsReadAsRgb) {
    const int w = 3, h = 2;
    const std::vector<float> r = {1, 2, 3, 4, 5, 6}, g = {0.5, 0.25, 0, 1, 2, 4},
                             b = {8, 7, 6, 5, 4, 3}, a = {0, 0, 0, 1, 1, 1};
    auto expectPlanes = [&](const Image& img, const std::vector<float>& pr,
                            const std::vector<float>& pg, const std::vector<float>& pb) {
        ASSERT_EQ(img.width, w);
        ASSERT_EQ(img.height, h);
        for (int i = 0; i < w * h; ++i)
            EXPECT_EQ(img.get(i % w, i / w), Rgb(pr[i], pg[i], pb[i])) << "texel " << i;
    };
    // RGBA half (values exact in half), alpha ignored, data window not at 0.
    writeExrChannels(path("rgba.exr"), w, h, {10, -3}, {{"R", r}, {"G", g}, {"B", b}, {"A", a}},
                     Imf::HALF);
    expectPlanes(readImage(path("rgba.exr")), r, g, b);
    // Y only: grey.
    writeExrChannels(path("y.exr"), w, h, {0, 0}, {{"Y", g}}, Imf::FLOAT);
    expectPlanes(readImage(path("y.exr")), g, g, g);
    // R and G only: B reads as 0.
    writeExrChannels(path("rg.exr"), w, h, {0, 0}, {{"R", r}, {"G", g}}, Imf::FLOAT);
    expectPlanes(readImage(path("rg.exr")), r, g, std::vector<float>(6, 0.0f));
    // Neither RGB nor Y; luminance/chroma.
    writeExrChannels(path("z.exr"), w, h, {0, 0}, {{"Z", r}}, Imf::FLOAT);
    expectInputError([&] { readImage(path("z.exr")); }, {path("z.exr"), "no R, G, B or Y"});
    writeExrChannels(path("yc.exr"), w, h, {0, 0}, {{"Y", r}, {"RY", g}, {"BY", b}}, Imf::HALF);
    expectInputError([&] { readImage(path("yc.exr")); }, {path("yc.exr"), "chroma"});
}

// A Radiance file written byte by byte: stb decodes a texel (m_r, m_g, m_b,
// e) as m * 2^(e - 136) (without the + 0.5 of Radiance's own reader).
std::string rgbeFile(int w, int h, const std::vector<std::array<uint8_t, 4>>& texels) {
    std::string out = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y " + std::to_string(h) + " +X " +
                      std::to_string(w) + "\n";
    for (const auto& t : texels) out.append(reinterpret_cast<const char*>(t.data()), 4);
    return out;
}

TEST_F(ImageFiles, HdrReadsFlatAndRunLengthFiles) {
    // 3 x 2, flat (narrower than 8 texels).
    const std::vector<std::array<uint8_t, 4>> texels = {{128, 64, 32, 129},  {128, 192, 0, 130},
                                                        {0, 0, 0, 0},        {255, 1, 17, 140},
                                                        {200, 100, 50, 120}, {16, 32, 64, 136}};
    writeFileAtomic(path("flat.hdr"), rgbeFile(3, 2, texels));
    const Image image = readImage(path("flat.hdr"));
    ASSERT_EQ(image.width, 3);
    ASSERT_EQ(image.height, 2);
    for (int i = 0; i < 6; ++i) {
        const auto& t = texels[i];
        const double f = t[3] == 0 ? 0.0 : std::ldexp(1.0, t[3] - 136);
        EXPECT_EQ(image.get(i % 3, i / 3), Rgb(t[0] * f, t[1] * f, t[2] * f)) << "texel " << i;
    }
    // Run-length encoded by stb_image_write; values that survive RGBE exactly.
    const Image rle = testing::rgbeExactImage();
    const std::string bytes = testing::radianceFileBytes(rle);
    writeFileAtomic(path("rle.HDR"), bytes);
    EXPECT_TRUE(sameBits(readImage(path("rle.HDR")), rle));
}

TEST_F(ImageFiles, MissingWrongOrGarbageFilesAreInputErrors) {
    expectInputError([&] { readImage(path("missing.exr")); }, {path("missing.exr")});
    expectInputError([&] { readImage(path("missing.hdr")); }, {path("missing.hdr")});
    writeFileAtomic(path("image.png"), "\x89PNG\r\n\x1a\n");
    expectInputError([&] { readImage(path("image.png")); }, {path("image.png"), "extension"});
    expectInputError([&] { readImage(path("noext")); }, {path("noext"), "extension"});
    std::string garbage;
    Rng rng(20, 20);
    for (int i = 0; i < 4096; ++i) garbage += static_cast<char>(rng.nextU32() & 0xff);
    for (const char* name : {"garbage.exr", "garbage.hdr", "empty.exr", "empty.hdr"}) {
        writeFileAtomic(path(name), std::string(name).starts_with("empty") ? "" : garbage);
        expectInputError([&] { readImage(path(name)); }, {path(name)});
    }
    // A PNG renamed .hdr is not decoded as an LDR image.
    Image small(2, 2);
    writePng(path("fake.hdr"), small);
    expectInputError([&] { readImage(path("fake.hdr")); }, {path("fake.hdr"), "Radiance"});
    // A directory.
    std::filesystem::create_directory(path("dir.exr"));
    expectInputError([&] { readImage(path("dir.exr")); }, {path("dir.exr")});
}

// OpenEXR allocates what a header claims (an attribute's size, one line
// offset per scanline block of the data window): weft checks those claims
// against the file and the limits first. tests/data/fuzz/ holds the libFuzzer
// findings that asked OpenEXR for more than 1 GB (issue 18).
TEST_F(ImageFiles, ExrHeadersClaimingHugeAllocationsAreInputErrors) {
    // Its attribute size; an attribute name longer than 31 characters that
    // OpenEXR would read in pieces; a 6.4 million texel wide, one-line image
    // whose ZIP decompressor wanted 1.2 GB (16 lines of the claimed width).
    for (const char* file :
         {"exr-header-oom.exr", "exr-long-name-oom.exr", "exr-decompressor-oom.exr"}) {
        const std::string finding =
            readFile(std::string(WEFT_SOURCE_DIR) + "/tests/data/fuzz/" + file);
        expectInputError([&] { decodeImage(finding, "finding.exr"); }, {"'finding.exr'"});
    }
    const std::string magic("\x76\x2f\x31\x01\x02\x00\x00\x00", 8);
    const auto attribute = [](const std::string& name, const std::string& type,
                              const std::string& value, uint32_t size) {
        std::string a = name + '\0' + type + '\0';
        for (int k = 0; k < 4; ++k) a += static_cast<char>(size >> (8 * k) & 0xff);
        return a + value;
    };
    expectInputError(
        [&] { decodeImage(magic + attribute("comment", "string", "x", 0x7fffffff), "a.exr"); },
        {"a.exr", "corrupt header: attribute 'comment' claims 2147483647 bytes"});
    std::string box;
    for (int32_t v : {0, 0, 99999, 99999})
        for (int k = 0; k < 4; ++k)
            box += static_cast<char>(static_cast<uint32_t>(v) >> (8 * k) & 0xff);
    expectInputError(
        [&] { decodeImage(magic + attribute("dataWindow", "box2i", box, 16) + '\0', "b.exr"); },
        {"b.exr", "100000 x 100000", "larger than"});
    expectInputError([&] { decodeImage(std::string("\x76\x2f\x31", 3), "c.exr"); }, {"c.exr"});
}

TEST_F(ImageFiles, TruncatedFilesAreInputErrors) {
    Image image(37, 23);
    Rng rng(21, 21);
    for (float& v : image.pixels) v = static_cast<float>(rng.uniform() * 4);
    writeExr(path("full.exr"), image);
    const std::string exr = readFile(path("full.exr"));
    for (size_t cut = 0; cut < exr.size(); cut += std::max<size_t>(1, exr.size() / 97)) {
        writeFileAtomic(path("cut.exr"), exr.substr(0, cut));
        expectInputError([&] { readImage(path("cut.exr")); }, {path("cut.exr")});
    }
    writeFileAtomic(path("cut.exr"), exr.substr(0, exr.size() - 1));
    expectInputError([&] { readImage(path("cut.exr")); }, {path("cut.exr")});

    // Radiance, run-length encoded and flat.
    const std::string rle = testing::radianceFileBytes(image);
    const std::vector<std::array<uint8_t, 4>> texels(6 * 40, {100, 50, 25, 130});
    const std::string flat = rgbeFile(6, 40, texels);
    for (const std::string* full : {&std::as_const(rle), &flat}) {
        writeFileAtomic(path("full.hdr"), *full);
        EXPECT_NO_THROW(readImage(path("full.hdr")));
        for (size_t cut = 0; cut < full->size(); cut += std::max<size_t>(1, full->size() / 97)) {
            writeFileAtomic(path("cut.hdr"), full->substr(0, cut));
            expectInputError([&] { readImage(path("cut.hdr")); }, {path("cut.hdr")});
        }
        for (size_t drop : {1, 2, 3, 4, 5}) {
            writeFileAtomic(path("cut.hdr"), full->substr(0, full->size() - drop));
            expectInputError([&] { readImage(path("cut.hdr")); }, {path("cut.hdr")});
        }
    }
    // Headers claiming far more texels than the file holds, or than allowed.
    writeFileAtomic(path("huge.hdr"), rgbeFile(20000, 10000, texels));
    expectInputError([&] { readImage(path("huge.hdr")); }, {path("huge.hdr"), "truncated"});
    writeFileAtomic(path("huge.hdr"), rgbeFile(100000, 100000, texels));
    expectInputError([&] { readImage(path("huge.hdr")); }, {path("huge.hdr"), "larger than"});
}

TEST_F(ImageFiles, HdrRunLengthRecordsAreChecked) {
    const std::string header = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 8\n";
    auto scanline = [](std::initializer_list<int> records) {
        std::string out = {2, 2, 0, 8};
        for (int b : records) out += static_cast<char>(b);
        return out;
    };
    // Each channel: a run of 8 (136 = 128 + 8) of one value; R G B E = 64 32 16 129.
    writeFileAtomic(path("ok.hdr"), header + scanline({136, 64, 136, 32, 136, 16, 136, 129}));
    const Image ok = readImage(path("ok.hdr"));
    for (int x = 0; x < 8; ++x) EXPECT_EQ(ok.get(x, 0), Rgb(0.5, 0.25, 0.125));
    // A record of length 0 (on which Debian's stb would loop forever).
    writeFileAtomic(path("zero.hdr"), header + scanline({0, 136, 64, 136, 32, 136, 16, 136, 129}));
    expectInputError([&] { readImage(path("zero.hdr")); }, {path("zero.hdr"), "length 0"});
    // A run longer than the scanline.
    writeFileAtomic(path("long.hdr"), header + scanline({137, 64, 136, 32, 136, 16, 136, 129}));
    expectInputError([&] { readImage(path("long.hdr")); }, {path("long.hdr")});
    // Literal records (count <= 128 bytes follow) mixed with runs.
    writeFileAtomic(path("mixed.hdr"),
                    header + scanline({4, 64, 64, 64, 64, 132, 64, 136, 32, 136, 16, 136, 129}));
    const Image mixed = readImage(path("mixed.hdr"));
    for (int x = 0; x < 8; ++x) EXPECT_EQ(mixed.get(x, 0), Rgb(0.5, 0.25, 0.125));
    // An old-style flat file of width >= 8 is read as flat texels.
    const std::vector<std::array<uint8_t, 4>> texels(8 * 2, {64, 32, 16, 129});
    writeFileAtomic(path("flat8.hdr"), rgbeFile(8, 2, texels));
    const Image flat = readImage(path("flat8.hdr"));
    ASSERT_EQ(flat.height, 2);
    EXPECT_EQ(flat.get(7, 1), Rgb(0.5, 0.25, 0.125));
}

TEST_F(ImageFiles, CorruptedBytesNeverCrash) {
    // Single-byte corruptions of valid files: each read either succeeds or
    // throws an InputError naming the file (never another exception).
    Image image(19, 11);
    Rng rng(22, 22);
    for (float& v : image.pixels) v = static_cast<float>(rng.uniform());
    writeExr(path("ok.exr"), image);
    const std::string hdr = testing::radianceFileBytes(image);
    for (const auto& [name, original] :
         {std::pair<std::string, std::string>{"bad.exr", readFile(path("ok.exr"))},
          std::pair<std::string, std::string>{"bad.hdr", hdr}}) {
        const int trials = static_cast<int>(scaled(3000) / 10);
        for (int k = 0; k < trials; ++k) {
            std::string bytes = original;
            const size_t at = rng.nextU32() % bytes.size();
            bytes[at] = static_cast<char>(rng.nextU32() & 0xff);
            writeFileAtomic(path(name), bytes);
            try {
                readImage(path(name));
            } catch (const InputError& e) {
                EXPECT_NE(std::string(e.what()).find(path(name)), std::string::npos) << e.what();
            } catch (const std::exception& e) {
                ADD_FAILURE() << name << " byte " << at << ": " << e.what();
            }
        }
    }
}

TEST_F(ImageFiles, WriteReportsErrors) {
    Image image(4, 2);
    expectInputError([&] { writeExr(path("no/such/dir/out.exr"), image); },
                     {path("no/such/dir/out.exr")});
    expectInputError([&] { writeExr(path("empty.exr"), Image()); }, {path("empty.exr")});
    Image wrongSize(4, 2);
    wrongSize.pixels.pop_back();
    expectInputError([&] { writeExr(path("short.exr"), wrongSize); },
                     {path("short.exr"), "4 x 2 texels with 23 values"});
    EXPECT_TRUE(filesIn(dir_).empty());
}

// ---------------------------------------------------------------------------
// Issue 41: what stb_image let through.

// A NaN or infinite pixel is refused by the readers themselves, so that every
// command that reads an image (compare, montage, render merge, envmaps) names
// the file and the first bad pixel: montage used to draw them black.
TEST_F(ImageFiles, NonFinitePixelsAreRefusedWhereImagesEnter) {
    Image image(4, 3);
    for (size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = 0.1f * i;
    Image nan = image, inf = image, negative = image;
    nan.pixels[3 * (4 * 2 + 1) + 1] = std::nanf("");
    inf.pixels[3 * 3 + 2] = INFINITY;
    inf.pixels[3 * (4 * 2 + 3)] = std::nanf("");  // a later one is not the first
    negative.pixels[0] = -INFINITY;
    writeExr(path("nan.exr"), nan);
    writeExr(path("inf.exr"), inf);
    writeExr(path("neg.exr"), negative);
    for (const auto& read : {std::function<Image(const std::string&)>(readImage),
                             std::function<Image(const std::string&)>(readImageOrPng)}) {
        expectInputError([&] { read(path("nan.exr")); },
                         {path("nan.exr"), "pixel (1, 2) channel G is NaN"});
        expectInputError([&] { read(path("inf.exr")); },
                         {path("inf.exr"), "pixel (3, 0) channel B is infinite"});
        expectInputError([&] { read(path("neg.exr")); },
                         {path("neg.exr"), "pixel (0, 0) channel R is infinite"});
    }
    expectInputError([&] { decodeImage(readFile(path("nan.exr")), "mem.exr"); },
                     {"mem.exr", "NaN"});
    writeExr(path("ok.exr"), image);
    EXPECT_TRUE(sameBits(readImageOrPng(path("ok.exr")), image));
}

// stb_image parses a Radiance resolution line with strtol and casts to int:
// "-Y 4294967312 +X 4294967312" was read as 16 x 16. Sizes are now read
// without wrapping and checked against the image limits.
TEST_F(ImageFiles, HdrSizesDoNotWrapAtTwoToThe32) {
    const std::string texels(16 * 16 * 4, '\x80');
    const auto file = [&](const std::string& resolution) {
        return "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + resolution + "\n" + texels;
    };
    writeFileAtomic(path("ok.hdr"), file("-Y 16 +X 16"));
    EXPECT_EQ(readImage(path("ok.hdr")).width, 16);
    for (const auto& [resolution, size] :
         {std::pair<std::string, std::string>{"-Y 4294967312 +X 4294967312",
                                              "4294967312 x 4294967312"},
          {"-Y 16 +X 4294967312", "4294967312 x 16"},
          {"-Y 4294967312 +X 16", "16 x 4294967312"},
          {"-Y 18446744073709551632 +X 16", "16 x 18446744073709551632"},
          {"-Y 16 +X 0", "0 x 16"},
          {"-Y -16 +X 16", "16 x -16"}}) {
        writeFileAtomic(path("wrap.hdr"), file(resolution));
        expectInputError([&] { readImage(path("wrap.hdr")); },
                         {path("wrap.hdr"), "size " + size, "texels"});
        expectInputError([&] { readImageOrPng(path("wrap.hdr")); }, {path("wrap.hdr"), size});
    }
}

// PNG files byte by byte: chunks with their CRC-32 (computed bit by bit here),
// image data compressed by stb_image_write's zlib.
extern "C" unsigned char* stbi_zlib_compress(unsigned char* data, int length, int* outLength,
                                             int quality);

uint32_t crc32BitByBit(const std::string& bytes) {
    uint32_t crc = 0xffffffffu;
    for (const char c : bytes) {
        crc ^= static_cast<unsigned char>(c);
        for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

std::string bigEndian32(uint32_t v) {
    return {static_cast<char>(v >> 24), static_cast<char>(v >> 16 & 0xff),
            static_cast<char>(v >> 8 & 0xff), static_cast<char>(v & 0xff)};
}

std::string pngChunk(const std::string& type, const std::string& data) {
    return bigEndian32(static_cast<uint32_t>(data.size())) + type + data +
           bigEndian32(crc32BitByBit(type + data));
}

// An 8-bit RGB PNG of w x h texels of grey `value` whose image data inflates
// to `surplus` bytes (zeros) more than the image needs.
std::string greyPng(int w, int h, unsigned char value, size_t surplus = 0) {
    std::string raw;
    for (int y = 0; y < h; ++y) raw += '\0' + std::string(3 * w, static_cast<char>(value));
    raw.append(surplus, '\0');
    int length = 0;
    unsigned char* z = stbi_zlib_compress(reinterpret_cast<unsigned char*>(raw.data()),
                                          static_cast<int>(raw.size()), &length, 8);
    const std::string zlib(reinterpret_cast<const char*>(z), length);
    std::free(z);
    const std::string header = bigEndian32(w) + bigEndian32(h) + std::string("\x08\x02\0\0\0", 5);
    return std::string("\x89PNG\r\n\x1a\n", 8) + pngChunk("IHDR", header) + pngChunk("IDAT", zlib) +
           pngChunk("IEND", "");
}

// stb_image checks no CRC and inflates image data beyond what the image
// needs: a PNG with a bad IHDR checksum, or with 200 MB of surplus image
// data, was read. The chunks are now walked first.
TEST_F(ImageFiles, PngChunksChecksumsAndImageDataAreChecked) {
    const std::string good = greyPng(5, 3, 200);
    const Image image = decodePng(good, "good.png");
    ASSERT_EQ(image.width, 5);
    ASSERT_EQ(image.height, 3);
    EXPECT_FLOAT_EQ(static_cast<float>(image.get(4, 2).g),
                    static_cast<float>(srgbToLinear(200 / 255.0)));
    // weft's own PNGs read back to the same bytes.
    Image ramp(7, 5);
    for (size_t i = 0; i < ramp.pixels.size(); ++i) ramp.pixels[i] = static_cast<float>(i) / 105;
    const std::string written = encodePng(ramp);
    EXPECT_EQ(encodePng(decodePng(written, "ramp.png")), written);

    std::string bad = good;
    bad[29] ^= 1;  // the IHDR's CRC (bytes 29-32)
    expectInputError([&] { decodePng(bad, "crc.png"); }, {"'crc.png'", "IHDR", "CRC"});
    bad = good;
    bad[16] ^= 1;  // the IHDR's width, its CRC kept
    expectInputError([&] { decodePng(bad, "crc.png"); }, {"'crc.png'", "IHDR", "CRC"});
    bad = good;
    bad[45] ^= 0x40;  // image data
    expectInputError([&] { decodePng(bad, "data.png"); }, {"'data.png'", "IDAT", "CRC"});
    // 1 MB of zeros after the image's 48 bytes of image data: IDAT chunks
    // larger than such an image can need, and (one byte more) data that
    // inflate to more than it needs.
    expectInputError([&] { decodePng(greyPng(5, 3, 200, 1 << 20), "surplus.png"); },
                     {"'surplus.png'", "IDAT chunks hold more than", "48 bytes"});
    expectInputError([&] { decodePng(greyPng(5, 3, 200, 1), "surplus.png"); },
                     {"'surplus.png'", "inflate to more than the 48 bytes"});
    // Bytes after IEND; no IEND; a chunk before IHDR.
    expectInputError([&] { decodePng(good + "trailing", "tail.png"); }, {"'tail.png'", "IEND"});
    expectInputError([&] { decodePng(good.substr(0, good.size() - 12), "end.png"); },
                     {"'end.png'", "IEND"});
    const std::string text = pngChunk("tEXt", std::string("a\0b", 3));
    expectInputError([&] { decodePng(good.substr(0, 8) + text + good.substr(8), "first.png"); },
                     {"'first.png'", "IHDR"});
    // An ancillary chunk in its place is fine.
    const size_t iend = good.size() - 12;
    EXPECT_EQ(decodePng(good.substr(0, iend) + text + good.substr(iend), "text.png").pixels,
              image.pixels);
}

}  // namespace
}  // namespace weft
