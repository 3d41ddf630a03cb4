#include "weft/core/curves.h"

#include <gtest/gtest.h>

#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <new>
#include <string>
#include <typeinfo>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/rng.h"
#include "weft/core/test_util.h"

// The corruption test checks that no single allocation made while parsing
// exceeds a small multiple of the input size, so this test program replaces
// the global operator new (the array and nothrow forms call it). Tracking is
// off except around the parse calls of that test.
namespace {
std::atomic<bool> gTrackAllocations{false};
std::atomic<size_t> gAllocationLimit{0};
std::atomic<size_t> gLargestAllocation{0};
}  // namespace

void* operator new(size_t n) {
    if (gTrackAllocations.load(std::memory_order_relaxed)) {
        size_t largest = gLargestAllocation.load(std::memory_order_relaxed);
        while (n > largest && !gLargestAllocation.compare_exchange_weak(largest, n)) {
        }
        // Refuse instead of asking the allocator for gigabytes: the test sees a
        // std::bad_alloc, which is not an InputError, and fails.
        if (n > gAllocationLimit.load(std::memory_order_relaxed)) throw std::bad_alloc();
    }
    if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
    throw std::bad_alloc();
}
// Not inlined: GCC would otherwise pair the inlined free() with the operator
// new at each call site and warn (-Wmismatched-new-delete) about a match that
// is correct for this replacement.
[[gnu::noinline]] void operator delete(void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, size_t) noexcept { std::free(p); }

namespace weft {
namespace {

using testing::expectInputError;
using CurvesTest = testing::TempDirTest;

const std::string kSharedDataDir = WEFT_CURVE_DATA_DIR;

// ---------------------------------------------------------------------------
// A BCC writer of its own, so that tests can build valid and broken files.

template <typename T>
void appendLittleEndian(std::string* out, T v) {
    char buf[sizeof v];
    std::memcpy(buf, &v, sizeof v);
    out->append(buf, sizeof v);
}

struct BccCurve {
    std::vector<float> xyz;  // 3 floats per point
    bool closed = false;
};

std::string bccHeader(const char* type, uint64_t curveCount, uint64_t pointCount) {
    std::string out = "BCC";
    out += static_cast<char>(0x44);
    out.append(type, 2);
    out += static_cast<char>(3);  // dimensions
    out += static_cast<char>(1);  // up direction: y
    appendLittleEndian<uint64_t>(&out, curveCount);
    appendLittleEndian<uint64_t>(&out, pointCount);
    out.append(40, '\0');
    return out;
}

std::string bccBytes(const char* type, const std::vector<BccCurve>& curves) {
    uint64_t points = 0;
    for (const BccCurve& c : curves) points += c.xyz.size() / 3;
    std::string out = bccHeader(type, curves.size(), points);
    for (const BccCurve& c : curves) {
        const auto n = static_cast<int32_t>(c.xyz.size() / 3);
        appendLittleEndian<int32_t>(&out, c.closed ? -n : n);
        for (float f : c.xyz) appendLittleEndian<float>(&out, f);
    }
    return out;
}

// Values that a sloppy float reader would not keep bit for bit.
const std::vector<BccCurve> kOpenAndClosed = {
    {{0.1f, -0.0f, 1e-40f,  // a denormal
      std::numeric_limits<float>::max(), -std::numeric_limits<float>::max(), 3.14159274f, -2.5f,
      1.0f / 3.0f, 7e-39f},
     false},
    {{1, 2, 3, 4, 5, 6, 7, 8, 9, -1, -2, -3}, true},
    {{0, 0, 0, 1, 0, 0}, true},  // 2-point closed curve: 2 segments
};

uint32_t floatBits(double v) { return std::bit_cast<uint32_t>(static_cast<float>(v)); }

void expectSameAsBcc(const CurveSet& set, const std::vector<BccCurve>& expected, CurveBasis basis) {
    ASSERT_EQ(set.curves.size(), expected.size());
    for (size_t i = 0; i < expected.size(); ++i) {
        const Curve& c = set.curves[i];
        EXPECT_EQ(c.closed, expected[i].closed) << "curve " << i;
        EXPECT_EQ(c.basis, basis) << "curve " << i;
        EXPECT_TRUE(c.radii.empty()) << "curve " << i;
        ASSERT_EQ(c.points.size() * 3, expected[i].xyz.size()) << "curve " << i;
        for (size_t j = 0; j < c.points.size(); ++j)
            for (int k = 0; k < 3; ++k) {
                // The double must hold the float exactly: compare the bits of
                // the round trip and the value itself.
                const float want = expected[i].xyz[3 * j + static_cast<size_t>(k)];
                EXPECT_EQ(floatBits(c.points[j][k]), std::bit_cast<uint32_t>(want))
                    << "curve " << i << " point " << j << " axis " << k;
                EXPECT_EQ(c.points[j][k], static_cast<double>(want));
            }
    }
}

TEST_F(CurvesTest, BccPolylineReadsBackBitExact) {
    writeFileAtomic(path("a.bcc"), bccBytes("PL", kOpenAndClosed));
    const CurveSet set = readCurves(path("a.bcc"));
    expectSameAsBcc(set, kOpenAndClosed, CurveBasis::Polyline);
    EXPECT_EQ(set.pointCount(), 9u);
    EXPECT_EQ(segmentCount(set), 2u + 4u + 2u);
    // -0.0 and +0.0 compare equal: check the sign bit survived.
    EXPECT_TRUE(std::signbit(set.curves[0].points[0].y));
}

TEST_F(CurvesTest, BccCatmullRomReadsBackBitExact) {
    // Upper-case extension on purpose: the dispatch ignores case.
    writeFileAtomic(path("b.BCC"), bccBytes("C0", kOpenAndClosed));
    expectSameAsBcc(readCurves(path("b.BCC")), kOpenAndClosed, CurveBasis::CatmullRom);
}

// Writes `contents` to `file` and expects readCurves to fail with an InputError
// whose message names the file and contains every part.
void expectReadError(const std::string& file, const std::string& contents,
                     std::initializer_list<std::string> parts) {
    writeFileAtomic(file, contents);
    try {
        readCurves(file);
        ADD_FAILURE() << file << " was accepted: '" << contents << "'";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find(file), std::string::npos) << "message '" << msg << "' lacks the file";
        for (const std::string& p : parts)
            EXPECT_NE(msg.find(p), std::string::npos)
                << "message '" << msg << "' lacks '" << p << "'";
    }
}

TEST_F(CurvesTest, BccHeaderErrorsNameTheByteOffset) {
    const std::string good = bccBytes("PL", kOpenAndClosed);
    const auto with = [&](size_t offset, std::string_view patch) {
        std::string b = good;
        b.replace(offset, patch.size(), patch);
        return b;
    };
    const auto u64 = [](uint64_t v) {
        std::string s;
        appendLittleEndian(&s, v);
        return s;
    };
    const std::string f = path("bad.bcc");
    expectReadError(f, good.substr(0, 10), {"byte offset 10", "truncated header"});
    expectReadError(f, with(0, "BCD"), {"byte offset 0", "signature 'BCD'"});
    expectReadError(f, with(3, "\x48"), {"byte offset 3", "0x48"});
    expectReadError(f, with(4, "C1"), {"byte offset 4", "'C1'"});
    expectReadError(f, with(6, std::string(1, '\2')), {"byte offset 6", "dimension count 2"});
    expectReadError(f, with(8, u64(0)), {"byte offset 8", "no curves"});
    expectReadError(f, with(8, u64(uint64_t{1} << 63)), {"byte offset 8", "at most"});
    expectReadError(f, with(8, u64(~uint64_t{0})), {"byte offset 8"});
    expectReadError(f, with(16, u64(uint64_t{1} << 62)), {"byte offset 16", "room"});
    expectReadError(f, with(16, u64(8)), {"byte offset 16", "declares 8", "hold 9"});
    // One more curve declared than present, and 4 bytes for its count: the
    // header bounds pass, the file runs out inside curve 3.
    std::string oneMore = with(8, u64(4));
    appendLittleEndian<int32_t>(&oneMore, 2);
    expectReadError(f, oneMore,
                    {"byte offset " + std::to_string(good.size()), "curve 3", "truncated"});
}

TEST_F(CurvesTest, BccCurveErrorsNameOffsetAndCurve) {
    const std::string good = bccBytes("PL", kOpenAndClosed);
    // Curve 1's count sits after the header and curve 0 (4 + 3 * 12 bytes).
    const size_t curve1 = 64 + 4 + 36;
    const auto withCount = [&](int32_t count) {
        std::string b = good;
        std::memcpy(b.data() + curve1, &count, 4);
        return b;
    };
    const std::string f = path("bad.bcc");
    const std::string at = "byte offset " + std::to_string(curve1);
    expectReadError(f, withCount(0), {at, "curve 1", "point count 0"});
    expectReadError(f, withCount(1), {at, "curve 1", "at least 2"});
    expectReadError(f, withCount(-1), {at, "curve 1"});
    expectReadError(f, withCount(std::numeric_limits<int32_t>::min()), {at, "curve 1"});
    expectReadError(f, withCount(std::numeric_limits<int32_t>::max()),
                    {at, "curve 1", "truncated"});
    // 7 points do not fit in the 76 bytes left; 5 would, reading into curve 2.
    expectReadError(f, withCount(7), {at, "curve 1", "truncated", "at most 6"});
    expectReadError(f, withCount(5), {"curve 1", "point 4", "non-finite"});
    // Fewer points than before: the rest reads as a bogus count or extra bytes.
    expectReadError(f, withCount(3), {"curve 2"});

    // Point 2 of curve 1, y coordinate.
    const size_t y = curve1 + 4 + 2 * 12 + 4;
    for (float bad :
         {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
          -std::numeric_limits<float>::infinity()}) {
        std::string b = good;
        std::memcpy(b.data() + y, &bad, 4);
        expectReadError(f, b,
                        {"byte offset " + std::to_string(y), "curve 1", "point 2", "non-finite y"});
    }
    expectReadError(f, good + "x",
                    {"byte offset " + std::to_string(good.size()), "1 unexpected bytes"});
}

TEST_F(CurvesTest, BccTruncatedAtEveryByteIsAnInputError) {
    const std::string good = bccBytes("C0", kOpenAndClosed);
    for (size_t n = 0; n < good.size(); ++n) {
        try {
            parseBccCurves(std::string_view(good).substr(0, n), "cut.bcc");
            ADD_FAILURE() << "a file cut to " << n << " bytes was accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("cut.bcc: byte offset "), std::string::npos)
                << e.what();
        }
    }
}

// ---------------------------------------------------------------------------
// The real yarn data in data/curves. The expected numbers were computed
// with an independent Python struct.unpack reader of the same files.

struct SharedBccFile {
    const char* name;
    size_t curves, points, segments;
    Vec3 lo, hi;
};

void checkSharedFile(const SharedBccFile& f) {
    const std::string file = kSharedDataDir + "/" + f.name;
    if (!std::filesystem::exists(file)) GTEST_SKIP() << file << " is missing";
    const CurveSet set = readCurves(file);
    EXPECT_EQ(set.curves.size(), f.curves);
    EXPECT_EQ(set.pointCount(), f.points);
    EXPECT_EQ(segmentCount(set), f.segments);
    for (const Curve& c : set.curves) {
        EXPECT_FALSE(c.closed);
        EXPECT_EQ(c.basis, CurveBasis::Polyline);
        EXPECT_TRUE(c.radii.empty());
    }
    const Bounds3 b = bounds(set);
    EXPECT_EQ(b.lo, f.lo);
    EXPECT_EQ(b.hi, f.hi);
}

TEST(CurvesSharedData, KnitStockinetteTiny) {
    checkSharedFile({"knit-stockinette-tiny.bcc",
                     22,
                     826,
                     804,
                     {-3.425945997238159, -1.9425586462020874, -1.5310457944869995},
                     {53.384342193603516, 33.185020446777344, 1.5195226669311523}});
    // Curve 0 has 7 points; its first, from the file's bytes bfd2f089 bff8a5c3 3f965fd2.
    const CurveSet set = readCurves(kSharedDataDir + "/knit-stockinette-tiny.bcc");
    ASSERT_EQ(set.curves[0].points.size(), 7u);
    EXPECT_EQ(set.curves[0].points[0],
              Vec3(std::bit_cast<float>(0xbfd2f089u), std::bit_cast<float>(0xbff8a5c3u),
                   std::bit_cast<float>(0x3f965fd2u)));
}

TEST(CurvesSharedData, WovenSatinSmall) {
    checkSharedFile({"woven-satin-small.bcc",
                     40,
                     4000,
                     3960,
                     {-5.951159954071045, -5.917449951171875, -2.306190013885498},
                     {39.64120864868164, 39.29418182373047, 2.3164799213409424}});
}

// ---------------------------------------------------------------------------
// Text

TEST_F(CurvesTest, TextWithRadiiCommentsAndClosedCurves) {
    writeFileAtomic(path("c.txt"),
                    "# two curves\n"
                    "0 0 0 0.5\n"
                    "1 0.1 -2 0.25  # trailing comment\r\n"
                    "  \t\n"
                    "\n"
                    "# closed\n"
                    "# another comment\n"
                    "1e3 +2 -3e-2 1\n"
                    "4 5 6 2\n"
                    "7 8 9 3\n");
    const CurveSet set = readCurves(path("c.txt"));
    ASSERT_EQ(set.curves.size(), 2u);
    EXPECT_FALSE(set.curves[0].closed);
    EXPECT_TRUE(set.curves[1].closed);
    EXPECT_EQ(set.curves[0].basis, CurveBasis::Polyline);
    EXPECT_EQ(set.curves[0].points, (std::vector<Vec3>{{0, 0, 0}, {1, 0.1, -2}}));
    EXPECT_EQ(set.curves[0].radii, (std::vector<double>{0.5, 0.25}));
    EXPECT_EQ(set.curves[1].points, (std::vector<Vec3>{{1e3, 2, -3e-2}, {4, 5, 6}, {7, 8, 9}}));
    EXPECT_EQ(set.curves[1].radii, (std::vector<double>{1, 2, 3}));
    EXPECT_EQ(segmentCount(set), 1u + 3u);
}

TEST_F(CurvesTest, TextWithoutRadii) {
    writeFileAtomic(path("d.txt"), "0 0 0\n1 1 1\n2 2 2");  // no final newline
    const CurveSet set = readCurves(path("d.txt"));
    ASSERT_EQ(set.curves.size(), 1u);
    EXPECT_EQ(set.curves[0].points.size(), 3u);
    EXPECT_TRUE(set.curves[0].radii.empty());
}

TEST_F(CurvesTest, TextErrorsNameFileAndLine) {
    const std::string f = path("e.txt");
    const auto expectError = [&](const std::string& text,
                                 std::initializer_list<std::string> parts) {
        expectReadError(f, text, parts);
    };
    expectError("0 0 0\n1 2\n", {f + ":2:", "expected a point 'x y z'"});
    expectError("0 0 0\n1 2 3 4 5\n", {f + ":2:", "3 or 4 numbers"});
    expectError("0 0 0\n1 2 x\n", {f + ":2:", "'1 2 x'"});
    expectError("0 0 0\n1,2,3\n", {f + ":2:"});
    expectError("0 0 0\nnan 0 0\n", {f + ":2:", "'nan'", "finite"});
    expectError("0 0 0\n0 inf 0\n", {f + ":2:", "'inf'"});
    expectError("0 0 0\n0 0 1e39\n", {f + ":2:", "float range"});
    expectError("0 0 0 1\n1 1 1 0\n", {f + ":2:", "radius '0'", "> 0"});
    expectError("0 0 0 -1\n1 1 1 1\n", {f + ":1:", "radius '-1'"});
    expectError("0 0 0 1\n1 1 1 inf\n", {f + ":2:", "radius 'inf'"});
    expectError("0 0 0 1\n1 1 1 1e-50\n", {f + ":2:", "radius '1e-50'"});  // 0 in float
    expectError("0 0 0 1\n1 1 1\n", {f + ":2:", "no radius", "line 1"});
    expectError("0 0 0\n1 1 1\n\n2 2 2 1\n3 3 3 1\n", {f + ":4:", "has a radius", "line 1"});
    expectError("# c\n0 0 0\n1 1 1\n\n\n2 2 2\n\n3 3 3\n4 4 4\n", {f + ":6:", "1 point"});
    expectError("0 0 0\n1 1 1\n\n2 2 2", {f + ":4:", "1 point"});
    expectError("", {f, "no curves"});
    expectError("# only comments\n\n", {f, "no curves"});
}

// ---------------------------------------------------------------------------
// OBJ

TEST_F(CurvesTest, ObjPolylines) {
    writeFileAtomic(path("f.obj"),
                    "# exported\n"
                    "mtllib yarn.mtl\n"
                    "o yarn\n"
                    "g group\n"
                    "s off\n"
                    "usemtl wool\n"
                    "v 0 0 0\n"
                    "v 1 0 0 1.0\n"          // with w
                    "v 1 1 0 0.5 0.5 0.5\n"  // with a vertex colour
                    "vn 0 0 1\n"
                    "vt 0.5 0.5\n"
                    "f 1 2 3\n"
                    "l 1 2 3\n"
                    "l 3/1 4\n"  // v/vt, forward reference to vertex 4
                    "v 2 2 2\r\n"
                    "l -1 -4  # relative: vertex 4 and vertex 1\n");
    const CurveSet set = readCurves(path("f.obj"));
    // Curves 0 and 1 share vertex 3 and are not merged.
    ASSERT_EQ(set.curves.size(), 3u);
    EXPECT_EQ(set.curves[0].points, (std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}));
    EXPECT_EQ(set.curves[1].points, (std::vector<Vec3>{{1, 1, 0}, {2, 2, 2}}));
    EXPECT_EQ(set.curves[2].points, (std::vector<Vec3>{{2, 2, 2}, {0, 0, 0}}));
    for (const Curve& c : set.curves) {
        EXPECT_FALSE(c.closed);
        EXPECT_TRUE(c.radii.empty());
        EXPECT_EQ(c.basis, CurveBasis::Polyline);
    }
    EXPECT_EQ(segmentCount(set), 4u);
}

TEST_F(CurvesTest, ObjErrorsNameFileAndLine) {
    const std::string f = path("g.obj");
    const auto expectError = [&](const std::string& text,
                                 std::initializer_list<std::string> parts) {
        expectReadError(f, text, parts);
    };
    expectError("v 0 0 0\nv 1 x 0\nl 1 2\n", {f + ":2:", "'v 1 x 0'"});
    expectError("v 0 0 0\nv 1 0\nl 1 2\n", {f + ":2:", "expected 'v x y z'"});
    expectError("v 0 0 0\nv 1 0 nan\nl 1 2\n", {f + ":2:", "'nan'"});
    expectError("v 0 0 0\nv 1 0 1e300\nl 1 2\n", {f + ":2:", "float range"});
    expectError("v 0 0 0\nv 1 0 0\n\nl 1 3\n", {f + ":4:", "index 3 out of range", "2 vertices"});
    expectError("v 0 0 0\nv 1 0 0\nl 1 -3\n", {f + ":3:", "-3 out of range"});
    expectError("v 0 0 0\nv 1 0 0\nl 1\n", {f + ":3:", "at least 2"});
    expectError("v 0 0 0\nv 1 0 0\nl 0 1\n", {f + ":3:", "invalid vertex index '0'"});
    expectError("v 0 0 0\nv 1 0 0\nl 1 1.5\n", {f + ":3:", "'1.5'"});
    expectError("v 0 0 0\nv 1 0 0\nl 1 99999999999999999999999\n", {f + ":3:"});
    expectError("v 0 0 0\nv 1 0 0\nf 1 2 1\n", {f, "no curves"});
}

// ---------------------------------------------------------------------------
// Writers: `weft ply`, `weft gather` (ply.txt) and `weft scene` write through
// them, and what they write must read back.

TEST_F(CurvesTest, BccWriterRewritesTheSharedFilesByteForByte) {
    // Both files carry this info string and up dimension 2 (z), so reading and
    // writing them again must give their bytes.
    for (const char* name : {"knit-stockinette-tiny.bcc", "woven-satin-small.bcc"}) {
        const std::string src = kSharedDataDir + "/" + name;
        if (!std::filesystem::exists(src)) GTEST_SKIP() << src << " is missing";
        writeBcc(path(name), readCurves(src), "tiled periodic yarn pattern");
        EXPECT_EQ(readFile(path(name)), readFile(src)) << name;
    }
}

TEST_F(CurvesTest, BccWriterKeepsBasisClosedCurvesAndInfo) {
    CurveSet set;
    set.curves = {{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}, {}, true, CurveBasis::CatmullRom, {}},
                  {{{0.5, 0.25, -3}, {4, 5, 6.5}}, {0.1, 0.2}, false, CurveBasis::CatmullRom, {}}};
    const std::string out = path("c0.bcc");
    writeBcc(out, set, std::string(100, 'i'));
    // The header by hand: signature, 4-byte values, "C0", 3 dimensions, up z,
    // 2 curves, 5 points, the info cut to 39 bytes and a NUL.
    const std::string bytes = readFile(out);
    ASSERT_EQ(bytes.size(), 64u + 2 * 4 + 5 * 12);
    EXPECT_EQ(bytes.substr(0, 8), std::string("BCC\x44"
                                              "C0\x03\x02",
                                              8));
    EXPECT_EQ(bytes.substr(8, 16), std::string("\x02\0\0\0\0\0\0\0\x05\0\0\0\0\0\0\0", 16));
    EXPECT_EQ(bytes.substr(24, 39), std::string(39, 'i'));
    EXPECT_EQ(bytes[63], '\0');
    int32_t first;
    std::memcpy(&first, bytes.data() + 64, 4);
    EXPECT_EQ(first, -3);  // closed
    const CurveSet back = readCurves(out);
    ASSERT_EQ(back.curves.size(), 2u);
    for (size_t i = 0; i < 2; ++i) {
        EXPECT_EQ(back.curves[i].points, set.curves[i].points) << i;
        EXPECT_EQ(back.curves[i].closed, set.curves[i].closed) << i;
        EXPECT_EQ(back.curves[i].basis, CurveBasis::CatmullRom) << i;
        EXPECT_TRUE(back.curves[i].radii.empty()) << i;  // BCC has no radii
    }
}

TEST_F(CurvesTest, WritersRefuseWhatTheReadersWouldRefuse) {
    const std::string out = path("w.bcc"), text = path("w.txt");
    const auto refused = [&](const CurveSet& set, std::initializer_list<std::string> bcc,
                             std::initializer_list<std::string> txt) {
        if (bcc.size()) expectInputError([&] { writeBcc(out, set, ""); }, bcc);
        if (txt.size()) expectInputError([&] { writeCurveText(text, set); }, txt);
    };
    CurveSet set;
    refused(set, {"cannot write '" + out + "'", "no curves"}, {text, "no curves"});
    set.curves = {{{{0, 0, 0}, {1, 1, 1}}, {}, false, CurveBasis::Polyline, {}},
                  {{{2, 2, 2}}, {}, false, CurveBasis::Polyline, {}}};
    refused(set, {out, "curve 1 has 1 point (a curve needs at least 2)"},
            {text, "curve 1 has 1 point"});
    set.curves[1].points.push_back({3, 3, 1e300});
    refused(set, {out, "curve 1 point 1", "not finite in float32"},
            {text, "curve 1 point 1", "float range"});
    set.curves[1].points[1].z = 3;
    set.curves[1].basis = CurveBasis::CatmullRom;
    refused(set, {out, "curve 1 and curve 0 have different bases"}, {});
    set.curves[1].radii = {0.5, 0.5};
    refused(set, {}, {text, "curve 1 has radii but curve 0 has none"});
    set.curves[0].radii = {0.5};
    refused(set, {}, {text, "curve 0 has 2 points but 1 radii"});
    set.curves[0].radii = {0.5, 1e-50};  // 0 in float32
    refused(set, {}, {text, "curve 0 point 1", "radius"});
    set.curves[0].radii = {0.5, 0.5};
    EXPECT_NO_THROW(writeCurveText(text, set));
    expectInputError([&] { writeCurveText(path("no/dir/x.txt"), set); }, {path("no/dir/x.txt")});
    EXPECT_FALSE(std::filesystem::exists(out));
}

// The text holds 9 significant digits: exact for float32 data, so each
// coordinate read back and rounded to float32 has the bits it had.
void expectSamePointsAsFloat(const Curve& back, const Curve& written, size_t curve) {
    ASSERT_EQ(back.points.size(), written.points.size()) << "curve " << curve;
    for (size_t j = 0; j < written.points.size(); ++j)
        for (int k = 0; k < 3; ++k)
            ASSERT_EQ(floatBits(back.points[j][k]), floatBits(written.points[j][k]))
                << "curve " << curve << " point " << j << " axis " << k;
}

TEST_F(CurvesTest, TextWriterRoundTrip) {
    const std::string knit = kSharedDataDir + "/knit-stockinette-tiny.bcc";
    if (!std::filesystem::exists(knit)) GTEST_SKIP() << knit << " is missing";
    CurveSet set = readCurves(knit);
    set.curves[3].closed = true;
    for (size_t i = 0; i < set.curves.size(); ++i)
        for (size_t j = 0; j < set.curves[i].points.size(); ++j)
            set.curves[i].radii.push_back(static_cast<float>(0.1 + 0.01 * double(i + j)));
    writeCurveText(path("knit.txt"), set);
    // Radii read back as float32: bit for bit.
    const CurveSet back = readCurves(path("knit.txt"));
    ASSERT_EQ(back.curves.size(), set.curves.size());
    for (size_t i = 0; i < set.curves.size(); ++i) {
        expectSamePointsAsFloat(back.curves[i], set.curves[i], i);
        EXPECT_EQ(back.curves[i].radii, set.curves[i].radii) << i;
        EXPECT_EQ(back.curves[i].closed, i == 3) << i;
    }
    // Float32 extremes too: FLT_MAX, whose %.9g (3.40282347e+38) lies beyond
    // the float range the reader allows, denormals, -0.
    const CurveSet extremes = parseBccCurves(bccBytes("PL", kOpenAndClosed), "x.bcc");
    writeCurveText(path("x.txt"), extremes);
    const CurveSet extremesBack = readCurves(path("x.txt"));
    ASSERT_EQ(extremesBack.curves.size(), extremes.curves.size());
    for (size_t i = 0; i < extremes.curves.size(); ++i) {
        expectSamePointsAsFloat(extremesBack.curves[i], extremes.curves[i], i);
        EXPECT_EQ(extremesBack.curves[i].closed, extremes.curves[i].closed) << i;
    }
    EXPECT_TRUE(std::signbit(extremesBack.curves[0].points[0].y));

    // Doubles come back to %.9g (and radii to float32); the text has a
    // header comment, "# closed" and a blank line between curves.
    CurveSet d;
    d.curves = {{{{0.1, 1.0 / 3.0, -2e-7}, {1e10, 0, 0}},
                 {0.123456789012, 1},
                 false,
                 CurveBasis::Polyline,
                 {}},
                {{{0, 0, 0}, {1, 1, 1}}, {2, 2}, true, CurveBasis::Polyline, {}}};
    EXPECT_EQ(formatCurveText(d, "d.txt"),
              "# weft curves: one 'x y z [radius]' point per line, a blank line between curves\n"
              "0.1 0.333333333 -2e-07 0.123456789\n"
              "1e+10 0 0 1\n"
              "\n"
              "# closed\n"
              "0 0 0 2\n"
              "1 1 1 2\n");
    const CurveSet dBack = parseTextCurves(formatCurveText(d, "d.txt"), "d.txt");
    EXPECT_NEAR(dBack.curves[0].points[0].y, 1.0 / 3.0, 1e-9);
    EXPECT_EQ(dBack.curves[0].radii[0], static_cast<float>(0.123456789));
    EXPECT_EQ(dBack.curves[0].points[1].x, 1e10);
    EXPECT_TRUE(dBack.curves[1].closed);
}

// ---------------------------------------------------------------------------
// Dispatch and helpers

TEST_F(CurvesTest, UnsupportedExtensionNamesFileAndAllowedOnes) {
    writeFileAtomic(path("h.ply"), "0 0 0\n1 1 1\n");
    expectInputError([&] { readCurves(path("h.ply")); },
                     {path("h.ply"), "'.ply'", ".bcc, .txt, .obj"});
    writeFileAtomic(path("noext"), "0 0 0\n1 1 1\n");
    expectInputError([&] { readCurves(path("noext")); }, {path("noext"), "(none)"});
    expectInputError([&] { readCurves(path("missing.bcc")); }, {path("missing.bcc")});
}

TEST(CurvesHelpers, SegmentCountAndBounds) {
    CurveSet set;
    EXPECT_EQ(segmentCount(set), 0u);
    EXPECT_TRUE(bounds(set).empty());
    set.curves.push_back({{{0, 0, 0}, {1, 2, 3}, {-1, 5, 0}}, {}, false, CurveBasis::Polyline, {}});
    set.curves.push_back({{{4, -2, 1}, {0, 0, 9}}, {}, true, CurveBasis::CatmullRom, {}});
    EXPECT_EQ(segmentCount(set.curves[0]), 2u);
    EXPECT_EQ(segmentCount(set.curves[1]), 2u);
    EXPECT_EQ(segmentCount(set), 4u);
    const Bounds3 b = bounds(set);
    EXPECT_FALSE(b.empty());
    EXPECT_EQ(b.lo, Vec3(-1, -2, 0));
    EXPECT_EQ(b.hi, Vec3(4, 5, 9));
}

// ---------------------------------------------------------------------------
// Randomized corruption: every mutated file must be read or rejected with an
// InputError; nothing else may escape, no sanitizer may fire, and no single
// allocation may exceed kAllocationFactor times the input size (plus slack).

constexpr size_t kAllocationFactor = 32;
constexpr size_t kAllocationSlack = 4096;

class Mutator {
  public:
    explicit Mutator(uint64_t stream) : rng_(stream, 20240607) {}

    size_t below(size_t n) {
        const uint64_t r = (uint64_t{rng_.nextU32()} << 32) | rng_.nextU32();
        return n == 0 ? 0 : static_cast<size_t>(r % n);
    }
    uint64_t u64() { return (uint64_t{rng_.nextU32()} << 32) | rng_.nextU32(); }

    // A count that is likely to hit an edge: small, negative, huge or random.
    uint64_t nastyCount() {
        switch (below(6)) {
            case 0:
                return below(8);
            case 1:
                return static_cast<uint64_t>(-static_cast<int64_t>(below(8)));
            case 2:
                return uint64_t{1} << below(64);
            case 3:
                return (uint64_t{1} << below(64)) - 1;
            case 4:
                return 0x80000000u;
            default:
                return u64();
        }
    }

    void byteMutation(std::string* s) {
        switch (below(5)) {
            case 0:  // truncate
                s->resize(below(s->size() + 1));
                break;
            case 1:  // flip a few bytes
                if (!s->empty())
                    for (size_t k = 0, n = 1 + below(4); k < n; ++k)
                        (*s)[below(s->size())] ^= static_cast<char>(1 + below(255));
                break;
            case 2: {  // insert garbage
                std::string junk;
                for (size_t k = 0, n = 1 + below(16); k < n; ++k)
                    junk += static_cast<char>(below(256));
                s->insert(below(s->size() + 1), junk);
                break;
            }
            case 3: {  // delete a range
                const size_t at = below(s->size() + 1);
                s->erase(at, below(32));
                break;
            }
            default:  // duplicate a range
                if (!s->empty()) {
                    const size_t at = below(s->size());
                    s->insert(below(s->size() + 1), s->substr(at, 1 + below(64)));
                }
        }
    }

    void bccMutation(std::string* s, const std::vector<size_t>& countOffsets) {
        const auto overwrite = [&](size_t offset, const void* v, size_t n) {
            if (offset + n <= s->size()) std::memcpy(s->data() + offset, v, n);
        };
        switch (below(5)) {
            case 0: {  // header curve count or point count
                const uint64_t v = nastyCount();
                overwrite(below(2) ? 8 : 16, &v, 8);
                break;
            }
            case 1: {  // a curve's point count
                const auto v = static_cast<uint32_t>(nastyCount());
                overwrite(countOffsets[below(countOffsets.size())], &v, 4);
                break;
            }
            case 2: {  // a non-finite or extreme float anywhere after the header
                const float specials[] = {
                    std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                    -std::numeric_limits<float>::infinity(), std::numeric_limits<float>::max(),
                    std::numeric_limits<float>::denorm_min()};
                if (s->size() > 68)
                    overwrite(64 + 4 * below((s->size() - 64) / 4), &specials[below(5)], 4);
                break;
            }
            case 3: {  // header bytes 0..7: signature, value size, type, dimensions
                const auto b = static_cast<char>(below(256));
                overwrite(below(8), &b, 1);
                break;
            }
            default:
                byteMutation(s);
        }
    }

    void lineMutation(std::string* s, const std::vector<std::string>& garbageLines) {
        // Split at line starts, then insert, delete, duplicate a line or
        // replace one number.
        std::vector<size_t> starts = {0};
        for (size_t i = 0; i < s->size(); ++i)
            if ((*s)[i] == '\n') starts.push_back(i + 1);
        const size_t at = starts[below(starts.size())];
        const size_t end = std::min(
            s->size(), s->find('\n', at) == std::string::npos ? s->size() : s->find('\n', at) + 1);
        switch (below(5)) {
            case 0:
            case 1:
                s->insert(at, garbageLines[below(garbageLines.size())] + "\n");
                break;
            case 2:
                s->erase(at, end - at);
                break;
            case 3:
                s->insert(at, s->substr(at, end - at));
                break;
            default: {  // replace the first digit run in the line with a nasty number
                const size_t digit = s->find_first_of("0123456789", at);
                if (digit != std::string::npos && digit < end) {
                    const size_t digitEnd = s->find_first_not_of("0123456789.", digit);
                    const std::string numbers[] = {
                        "0",           "-0",         "1e400",
                        "-1e-400",     "nan",        "99999999999999999999",
                        "-2147483649", "4294967297", std::to_string(u64())};
                    s->replace(digit, std::min(digitEnd, end) - digit, numbers[below(9)]);
                }
            }
        }
    }

  private:
    Rng rng_;
};

struct FuzzTally {
    size_t cases = 0, accepted = 0, rejected = 0, failed = 0;
    std::vector<std::string> failures;  // the first few, for the message
};

// Parses one mutated input with allocation tracking on; any outcome other than
// success or InputError is recorded as a failure.
template <typename Parse>
void runCase(const std::string& input, const Parse& parse, FuzzTally* tally) {
    ++tally->cases;
    gLargestAllocation = 0;
    gAllocationLimit = kAllocationFactor * input.size() + kAllocationSlack;
    gTrackAllocations = true;
    std::string failure;
    try {
        const CurveSet set = parse(input);
        gTrackAllocations = false;
        ++tally->accepted;
        // Whatever was accepted must be usable: every curve has >= 2 points.
        for (const Curve& c : set.curves)
            if (c.points.size() < 2 || (!c.radii.empty() && c.radii.size() != c.points.size()))
                failure = "accepted a malformed curve";
    } catch (const InputError&) {
        gTrackAllocations = false;
        ++tally->rejected;
    } catch (const std::exception& e) {
        gTrackAllocations = false;
        failure = std::string("threw ") + typeid(e).name() + ": " + e.what() +
                  " (largest allocation " + std::to_string(gLargestAllocation) + " bytes)";
    }
    if (failure.empty()) return;
    ++tally->failed;
    if (tally->failures.size() < 10)
        tally->failures.push_back("case " + std::to_string(tally->cases) + " (" +
                                  std::to_string(input.size()) + " bytes): " + failure);
}

void expectClean(const char* format, const FuzzTally& t) {
    std::printf("[ corrupt  ] %s: %zu cases, %zu read, %zu rejected with InputError\n", format,
                t.cases, t.accepted, t.rejected);
    EXPECT_EQ(t.failed, 0u) << format << ": " << t.failed << " failures, first: "
                            << (t.failures.empty() ? "" : t.failures.front());
    // Both outcomes must occur, or the mutations are not testing anything.
    EXPECT_GT(t.accepted, t.cases / 100) << format;
    EXPECT_GT(t.rejected, t.cases / 10) << format;
}

TEST_F(CurvesTest, RandomCorruptionIsReadOrRejectedWithInputError) {
    const auto start = std::chrono::steady_clock::now();
    constexpr size_t kBccCases = 6000, kTextCases = 2500, kObjCases = 2500;

    // BCC: the synthetic file in both bases, plus the real knit when present.
    std::vector<std::string> bccInputs = {bccBytes("PL", kOpenAndClosed),
                                          bccBytes("C0", kOpenAndClosed)};
    const std::string knit = kSharedDataDir + "/knit-stockinette-tiny.bcc";
    if (std::filesystem::exists(knit)) bccInputs.push_back(readFile(knit));
    FuzzTally bcc;
    Mutator m(1);
    for (size_t i = 0; i < kBccCases; ++i) {
        std::string s = bccInputs[i % bccInputs.size()];
        // Curve count offsets of the unmutated file, to aim count overwrites.
        std::vector<size_t> countOffsets;
        for (size_t offset = 64; offset + 4 <= s.size();) {
            countOffsets.push_back(offset);
            int32_t n;
            std::memcpy(&n, s.data() + offset, 4);
            offset += 4 + 12 * static_cast<size_t>(std::abs(static_cast<int64_t>(n)));
        }
        for (size_t k = 0, n = 1 + m.below(3); k < n; ++k) m.bccMutation(&s, countOffsets);
        runCase(
            s, [](const std::string& b) { return parseBccCurves(b, "fuzz.bcc"); }, &bcc);
    }
    expectClean("bcc", bcc);

    const std::vector<std::string> garbage = {"",
                                              "#",
                                              "# closed",
                                              "1 2",
                                              "1 2 3",
                                              "1 2 3 4",
                                              "1 2 3 -1",
                                              "1 2 3 0",
                                              "nan 1 2",
                                              "1 2 3 4 5",
                                              "v 1 2 3",
                                              "v 1e400 0 0",
                                              "v 1 2",
                                              "l 1",
                                              "l 0 1",
                                              "l 1 -1",
                                              "l -99 1",
                                              "l 999999999 1",
                                              "l 1 99999999999999999999",
                                              "l 1/2/3 2//1",
                                              "f 1 2 3",
                                              "\x01\xff\x80",
                                              "l",
                                              "v",
                                              std::string(300, '9')};

    FuzzTally text;
    const std::string goodText =
        "# test\n0 0 0 1\n1 0 0 1\n2 1 0 0.5\n\n# closed\n0 1 0 1\n1 1 1 2\n-1 -1 -1 3\n\n"
        "5 5 5 1\n6 6 6 1\n";
    ASSERT_EQ(parseTextCurves(goodText, "t.txt").curves.size(), 3u);
    for (size_t i = 0; i < kTextCases; ++i) {
        std::string s = goodText;
        for (size_t k = 0, n = 1 + m.below(3); k < n; ++k)
            m.below(2) ? m.lineMutation(&s, garbage) : m.byteMutation(&s);
        runCase(
            s, [](const std::string& t) { return parseTextCurves(t, "fuzz.txt"); }, &text);
    }
    expectClean("txt", text);

    FuzzTally obj;
    const std::string goodObj =
        "# test\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvn 0 0 1\nv 0 1 1\nl 1 2 3\nl 3 4\nl -1 -2 -3 -4\n"
        "f 1 2 3\nl 4/1 1/2\n";
    ASSERT_EQ(parseObjCurves(goodObj, "o.obj").curves.size(), 4u);
    for (size_t i = 0; i < kObjCases; ++i) {
        std::string s = goodObj;
        for (size_t k = 0, n = 1 + m.below(3); k < n; ++k)
            m.below(2) ? m.lineMutation(&s, garbage) : m.byteMutation(&s);
        runCase(
            s, [](const std::string& t) { return parseObjCurves(t, "fuzz.obj"); }, &obj);
    }
    expectClean("obj", obj);

    // A few through readCurves and a real file, dispatch included.
    FuzzTally files;
    for (size_t i = 0; i < 30; ++i) {
        std::string s = bccInputs[0];
        m.bccMutation(&s, {64});
        writeFileAtomic(path("fuzz.bcc"), s);
        runCase(
            s, [&](const std::string&) { return readCurves(path("fuzz.bcc")); }, &files);
    }
    for (const std::string& f : files.failures) ADD_FAILURE() << f;

    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const size_t total = bcc.cases + text.cases + obj.cases + files.cases;
    std::printf("[ corrupt  ] %zu mutated files in %.2f s\n", total, seconds);
    EXPECT_GE(total, 10000u);
}

}  // namespace
}  // namespace weft
