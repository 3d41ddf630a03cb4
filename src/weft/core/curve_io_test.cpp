#include "weft/core/curve_io.h"

#include <gtest/gtest.h>

#include "weft/core/test_util.h"
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <limits>
#include <string>

#include "weft/core/error.h"
#include "weft/core/file.h"

namespace weft {
namespace {

namespace fs = std::filesystem;

const std::string kDataDir = WEFT_CURVE_DATA_DIR;

using CurveIoTest = testing::TempDirTest;

using testing::expectInputError;

// Text holds 9 significant digits: exact for float32 values, so compare as floats.
void expectSameCurvesAsFloat(const CurveSet& a, const CurveSet& b) {
    ASSERT_EQ(a.curves.size(), b.curves.size());
    for (size_t i = 0; i < a.curves.size(); ++i) {
        ASSERT_EQ(a.curves[i].size(), b.curves[i].size()) << "curve " << i;
        EXPECT_EQ(a.isClosed(i), b.isClosed(i)) << "curve " << i;
        ASSERT_EQ(a.hasRadii(i), b.hasRadii(i)) << "curve " << i;
        for (size_t j = 0; j < a.curves[i].size(); ++j) {
            for (int k = 0; k < 3; ++k)
                ASSERT_EQ(static_cast<float>(a.curves[i][j][k]),
                          static_cast<float>(b.curves[i][j][k]))
                    << "curve " << i << " point " << j;
            if (a.hasRadii(i)) {
                ASSERT_EQ(static_cast<float>(a.radii[i][j]), static_cast<float>(b.radii[i][j]));
            }
        }
    }
}

void expectSameCurves(const CurveSet& a, const CurveSet& b) {
    ASSERT_EQ(a.curves.size(), b.curves.size());
    EXPECT_EQ(a.basis, b.basis);
    for (size_t i = 0; i < a.curves.size(); ++i) {
        EXPECT_EQ(a.curves[i], b.curves[i]) << "curve " << i;
        EXPECT_EQ(a.isClosed(i), b.isClosed(i)) << "curve " << i;
        EXPECT_EQ(a.hasRadii(i), b.hasRadii(i)) << "curve " << i;
        if (a.hasRadii(i) && b.hasRadii(i)) {
            EXPECT_EQ(a.radii[i], b.radii[i]) << "curve " << i;
        }
    }
}

// A BCC file built by hand: header fields as given, then the body bytes.
std::string bccHeader(std::string_view sign, unsigned char byteCount, std::string_view type,
                      char dims, uint64_t curves, uint64_t points) {
    std::string h(64, '\0');
    std::memcpy(h.data(), sign.data(), 3);
    h[3] = static_cast<char>(byteCount);
    std::memcpy(h.data() + 4, type.data(), 2);
    h[6] = dims;
    h[7] = 2;
    std::memcpy(h.data() + 8, &curves, 8);
    std::memcpy(h.data() + 16, &points, 8);
    return h;
}

void appendCurve(std::string* out, int32_t count, const std::vector<float>& xyz) {
    out->append(reinterpret_cast<const char*>(&count), 4);
    out->append(reinterpret_cast<const char*>(xyz.data()), xyz.size() * sizeof(float));
}

// ---------------------------------------------------------------------------
// BCC

TEST_F(CurveIoTest, ReadsRealKnitFile) {
    const CurveSet set = readBcc(kDataDir + "/knit-stockinette-tiny.bcc");
    EXPECT_EQ(set.curves.size(), 22u);
    EXPECT_EQ(set.pointCount(), 826u);
    EXPECT_EQ(set.basis, CurveSet::Basis::Polyline);
    ASSERT_EQ(set.closed.size(), 22u);
    ASSERT_EQ(set.radii.size(), 22u);
    EXPECT_EQ(set.curves[0].size(), 7u);
    // First point, read from the file's bytes: bfd2f089 bff8a5c3 3f965fd2.
    EXPECT_FLOAT_EQ(static_cast<float>(set.curves[0][0].x), -1.6479655f);
    for (size_t i = 0; i < set.curves.size(); ++i) {
        EXPECT_FALSE(set.hasRadii(i));
        for (const Vec3& p : set.curves[i]) {
            EXPECT_TRUE(isFinite(p));
            EXPECT_LT(std::fabs(p.x) + std::fabs(p.y) + std::fabs(p.z), 1e3);
        }
    }
}

TEST_F(CurveIoTest, ReadsRealSatinFile) {
    const CurveSet set = readBcc(kDataDir + "/woven-satin-small.bcc");
    EXPECT_EQ(set.curves.size(), 40u);
    EXPECT_EQ(set.pointCount(), 4000u);
    EXPECT_EQ(set.basis, CurveSet::Basis::Polyline);
}

TEST_F(CurveIoTest, BccRoundTripIsByteExact) {
    for (const char* name : {"knit-stockinette-tiny.bcc", "woven-satin-small.bcc"}) {
        const std::string src = kDataDir + "/" + name;
        const CurveSet set = readBcc(src);
        const std::string out = path(name);
        writeBcc(out, set, "tiled periodic yarn pattern");
        expectSameCurves(readBcc(out), set);
        // Both files carry this info string and use upDimension 2, so the
        // rewrite reproduces them byte for byte.
        EXPECT_EQ(readFile(out), readFile(src)) << name;
    }
}

TEST_F(CurveIoTest, BccClosedCatmullRomAndInfo) {
    CurveSet set;
    set.basis = CurveSet::Basis::CatmullRom;
    set.curves = {{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}, {{0.5, 0.25, -3}}};
    set.closed = {true, false};
    const std::string out = path("c0.bcc");
    writeBcc(out, set, std::string(100, 'i'));
    const std::string bytes = readFile(out);
    EXPECT_EQ(bytes.substr(0, 7), std::string("BCC\x44"
                                              "C0\x03",
                                              7));
    EXPECT_EQ(bytes.substr(24, 39), std::string(39, 'i'));
    EXPECT_EQ(bytes[63], '\0');
    int32_t first;
    std::memcpy(&first, bytes.data() + 64, 4);
    EXPECT_EQ(first, -3);
    const CurveSet back = readBcc(out);
    expectSameCurves(back, set);

    // Writing refuses what BCC cannot hold.
    set.curves[1][0].y = 1e300;
    expectInputError([&] { writeBcc(out, set, ""); }, {out, "curve 1 point 0", "float32"});
    set.curves[1].clear();
    expectInputError([&] { writeBcc(out, set, ""); }, {out, "curve 1 has no points"});
    expectInputError([&] { writeBcc(path("no/dir/x.bcc"), CurveSet{}, ""); },
                     {path("no/dir/x.bcc")});
}

TEST_F(CurveIoTest, BccRejectsCorruptFiles) {
    const std::string p = path("knit.bcc");
    const auto check = [&](const std::string& bytes, std::initializer_list<std::string> parts) {
        writeFileAtomic(p, bytes);
        expectInputError([&] { readBcc(p); }, {p});
        expectInputError([&] { readBcc(p); }, parts);
    };
    const std::vector<float> tri = {0, 0, 0, 1, 0, 0, 1, 1, 0};
    std::string body;
    appendCurve(&body, 3, tri);
    appendCurve(&body, -3, tri);
    // The valid file, to be sure the cases below fail for the reason named.
    writeFileAtomic(p, bccHeader("BCC", 0x44, "PL", 3, 2, 6) + body);
    const CurveSet ok = readBcc(p);
    EXPECT_EQ(ok.closed, (std::vector<bool>{false, true}));

    check("", {"truncated", "64 bytes"});
    check(bccHeader("BCC", 0x44, "PL", 3, 2, 6).substr(0, 40), {"truncated"});
    check(bccHeader("HAI", 0x44, "PL", 3, 2, 6) + body, {"not a BCC file", "'HAI'"});
    check(bccHeader("BCC", 0x88, "PL", 3, 2, 6) + body, {"byte count 0x88", "0x44"});
    check(bccHeader("BCC", 0x44, "BZ", 3, 2, 6) + body, {"curve type 'BZ'", "PL", "C0"});
    check(bccHeader("BCC", 0x44, "PL", 2, 2, 6) + body, {"dimension count 2"});
    // Truncated inside the second curve's points: 1 of its 3 points is there.
    check(bccHeader("BCC", 0x44, "PL", 3, 2, 6) + body.substr(0, body.size() - 20),
          {"truncated: curve 1 declares 3 points but the file ends after 1"});
    // Truncated before the second curve's count.
    check(bccHeader("BCC", 0x44, "PL", 3, 3, 9) + body + "\x03",
          {"truncated", "point count of curve 2"});
    check(bccHeader("BCC", 0x44, "PL", 3, 1000000, 6) + body, {"truncated", "1000000 curves"});
    check(bccHeader("BCC", 0x44, "PL", 3, 1, 3) + body, {"40 unexpected bytes", "1 curves"});
    check(bccHeader("BCC", 0x44, "PL", 3, 2, 7) + body, {"declares 7 control points", "hold 6"});
    std::string zero;
    appendCurve(&zero, 0, {});
    check(bccHeader("BCC", 0x44, "PL", 3, 1, 0) + zero, {"curve 0", "invalid point count 0"});
    std::vector<float> bad = tri;
    bad[4] = std::numeric_limits<float>::quiet_NaN();
    std::string nanBody;
    appendCurve(&nanBody, 3, bad);
    check(bccHeader("BCC", 0x44, "PL", 3, 1, 3) + nanBody, {"curve 0 point 1", "non-finite"});
    bad[4] = std::numeric_limits<float>::infinity();
    nanBody.clear();
    appendCurve(&nanBody, 3, bad);
    check(bccHeader("BCC", 0x44, "PL", 3, 1, 3) + nanBody, {"non-finite"});

    // The real file cut short.
    const std::string real = readFile(kDataDir + "/knit-stockinette-tiny.bcc");
    check(real.substr(0, real.size() - 30), {"truncated: curve 21 declares"});
    expectInputError([&] { readBcc(path("missing.bcc")); }, {path("missing.bcc")});
}

// ---------------------------------------------------------------------------
// Text

TEST_F(CurveIoTest, TextParsesCurvesCommentsAndRadii) {
    const std::string text =
        "# a comment\n"
        "0 0 0\n"
        "1 0 0   \n"
        "\t1.5e0 -2 +3\n"
        "\n"
        "\n"
        "# closed\n"
        "0 0 1 0.5\r\n"
        "# a comment inside a curve does not split it\n"
        "1 0 1 0.25\n"
        "   \n"
        "7 8 9";
    const CurveSet set = parseCurveText(text, "mem.txt");
    ASSERT_EQ(set.curves.size(), 3u);
    EXPECT_EQ(set.curves[0], (std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {1.5, -2, 3}}));
    EXPECT_EQ(set.curves[1], (std::vector<Vec3>{{0, 0, 1}, {1, 0, 1}}));
    EXPECT_EQ(set.curves[2], (std::vector<Vec3>{{7, 8, 9}}));
    EXPECT_EQ(set.radii[0], std::vector<double>{});
    EXPECT_EQ(set.radii[1], (std::vector<double>{0.5, 0.25}));
    EXPECT_EQ(set.closed, (std::vector<bool>{false, true, false}));
    EXPECT_EQ(set.basis, CurveSet::Basis::Polyline);
    EXPECT_TRUE(parseCurveText("", "empty.txt").curves.empty());
    EXPECT_TRUE(parseCurveText("# only\n\n#comments\n", "c.txt").curves.empty());
}

TEST_F(CurveIoTest, TextErrorsNameFileAndLine) {
    const auto check = [&](const std::string& text, const std::string& where,
                           std::initializer_list<std::string> parts) {
        expectInputError([&] { parseCurveText(text, "ply.txt"); }, {where});
        expectInputError([&] { parseCurveText(text, "ply.txt"); }, parts);
    };
    check("0 0 0\nx 1 2\n", "ply.txt:2: ", {"expected 3 or 4 numbers", "got 'x 1 2'"});
    check("0 0\n", "ply.txt:1: ", {"expected 3 or 4 numbers", "got '0 0'"});
    check("1 2 3 4 5\n", "ply.txt:1: ", {"got '1 2 3 4 5'"});
    check("1 2 3,\n", "ply.txt:1: ", {"got '1 2 3,'"});
    check("\n\n1 2 nan\n", "ply.txt:3: ", {"non-finite", "'nan'"});
    check("1 2 inf\n", "ply.txt:1: ", {"non-finite"});
    check("1e999 2 3\n", "ply.txt:1: ", {"expected 3 or 4 numbers"});
    check("1 2 3 -0.1\n", "ply.txt:1: ", {"negative radius -0.1"});
    check("# c\n1 2 3 0.1\n1 2 3\n", "ply.txt:3: ", {"no radius", "from line 2"});
    check("1 2 3\n1 2 3 0.1\n", "ply.txt:2: ", {"has a radius", "from line 1"});
    // Different curves may differ.
    EXPECT_NO_THROW(parseCurveText("1 2 3\n\n1 2 3 0.1\n", "ply.txt"));
    expectInputError([&] { readCurveText(path("missing.txt")); }, {path("missing.txt")});
}

TEST_F(CurveIoTest, TextRoundTrip) {
    CurveSet set = readBcc(kDataDir + "/knit-stockinette-tiny.bcc");
    set.closed[3] = true;
    set.radii[2].assign(set.curves[2].size(), 0.0);
    for (size_t j = 0; j < set.radii[2].size(); ++j)
        set.radii[2][j] = static_cast<float>(0.1 + 0.01 * double(j));
    const std::string p = path("knit.txt");
    writeCurveText(p, set);
    // %.9g is exact for float32 data.
    expectSameCurvesAsFloat(readCurveText(p), set);

    // Doubles come back to %.9g.
    CurveSet d;
    d.curves = {{{0.1, 1.0 / 3.0, -2e-7}, {1e10, 0, 0}}};
    d.radii = {{0.123456789012, 1}};
    const CurveSet back = parseCurveText(formatCurveText(d), "d.txt");
    ASSERT_EQ(back.curves.size(), 1u);
    EXPECT_NEAR(back.curves[0][0].y, 1.0 / 3.0, 1e-9);
    EXPECT_NEAR(back.radii[0][0], 0.123456789012, 1e-9);
    EXPECT_EQ(back.curves[0][1].x, 1e10);

    CurveSet mismatch;
    mismatch.curves = {{{0, 0, 0}, {1, 1, 1}}};
    mismatch.radii = {{1}};
    expectInputError([&] { writeCurveText(p, mismatch); }, {p, "2 points but 1 radii"});
}

// ---------------------------------------------------------------------------
// OBJ

TEST_F(CurveIoTest, ObjPolylines) {
    const std::string p = path("curves.obj");
    writeFileAtomic(p,
                    "# exported\n"
                    "o yarn\n"
                    "v 0 0 0\n"
                    "v 1 0 0\n"
                    "v 1 1 0 1.0\n"
                    "vn 0 0 1\n"
                    "vt 0.5 0.5\n"
                    "f 1 2 3\n"
                    "l 1 2 3\n"
                    "v 2 2 2\r\n"
                    "l -1 -2 \\\n"
                    "  1   # continued\n"
                    "l 4/1 1/2\n"
                    "l 5 1\n"
                    "v 9 9 9\n");
    const CurveSet set = readObjCurves(p);
    ASSERT_EQ(set.curves.size(), 4u);
    EXPECT_EQ(set.curves[0], (std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}));
    EXPECT_EQ(set.curves[1], (std::vector<Vec3>{{2, 2, 2}, {1, 1, 0}, {0, 0, 0}}));
    EXPECT_EQ(set.curves[2], (std::vector<Vec3>{{2, 2, 2}, {0, 0, 0}}));
    // Positive indices may refer to vertices defined later in the file.
    EXPECT_EQ(set.curves[3], (std::vector<Vec3>{{9, 9, 9}, {0, 0, 0}}));
    EXPECT_EQ(set.closed, (std::vector<bool>(4, false)));
    EXPECT_EQ(set.radii.size(), 4u);
}

TEST_F(CurveIoTest, ObjErrorsNameFileAndLine) {
    const std::string p = path("bad.obj");
    const auto check = [&](const std::string& text, const std::string& where,
                           std::initializer_list<std::string> parts) {
        writeFileAtomic(p, text);
        expectInputError([&] { readObjCurves(p); }, {p + where});
        expectInputError([&] { readObjCurves(p); }, parts);
    };
    check("v 0 0 0\nv 1 1 1\nl 1 3\n", ":3: ", {"vertex index 3 out of range", "2 vertices"});
    check("v 0 0 0\nl 1 0\n", ":2: ", {"invalid vertex index '0'"});
    check("v 0 0 0\nl 1 -2\n", ":2: ", {"relative vertex index -2"});
    check("v 0 0 0\nl 1 a\n", ":2: ", {"invalid vertex index 'a'"});
    check("v 0 0 0\nl 1\n", ":2: ", {"at least 2"});
    check("\nv 0 0\n", ":2: ", {"expected 'v x y z'"});
    check("v 0 nan 0\n", ":1: ", {"non-finite"});
    expectInputError([&] { readObjCurves(path("missing.obj")); }, {path("missing.obj")});
}

}  // namespace
}  // namespace weft
