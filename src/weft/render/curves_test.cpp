#include "weft/render/curves.h"

#include <gtest/gtest.h>

#include <initializer_list>
#include <string>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/test_util.h"

namespace weft::render {
namespace {

using testing::expectInputError;
using CurvesTest = testing::TempDirTest;

// A scene's vertex colour file (docs/scene-format.md, "vertex_colours").
TEST_F(CurvesTest, VertexColoursFollowTheCurvesPointByPoint) {
    CurveSet set = parseTextCurves("0 0 0\n1 0 0\n2 0 0\n\n0 1 0\n1 1 0\n", "c.txt");
    writeFileAtomic(path("dye.txt"),
                    "# two curves\n1 0 0\n0.5 0.25 0  # a comment\n0 0 1\n\n\n+1 1 1\n0 0 0\n");
    readVertexColours(path("dye.txt"), &set);
    ASSERT_EQ(set.curves[0].colours.size(), 3u);
    EXPECT_EQ(set.curves[0].colours[1], Rgb(0.5, 0.25, 0));
    EXPECT_EQ(set.curves[0].colours[2], Rgb(0, 0, 1));
    EXPECT_EQ(set.curves[1].colours, (std::vector<Rgb>{Rgb(1), Rgb(0)}));

    const std::string f = path("bad.txt");
    const auto expectError = [&](const std::string& text,
                                 std::initializer_list<std::string> parts) {
        CurveSet fresh = parseTextCurves("0 0 0\n1 0 0\n2 0 0\n\n0 1 0\n1 1 0\n", "c.txt");
        writeFileAtomic(f, text);
        expectInputError([&] { readVertexColours(f, &fresh); }, parts);
        EXPECT_TRUE(fresh.curves[0].colours.empty());  // nothing assigned on failure
    };
    expectError("1 0 0\n1 0\n", {f + ":2:", "'r g b'", "'1 0'"});
    expectError("1 0 0\n1 0 0 1\n", {f + ":2:", "3 numbers"});
    expectError("1 0 0\n1 x 0\n", {f + ":2:", "'1 x 0'"});
    expectError("1 0 0\n1 1.5 0\n", {f + ":2:", "'1.5'", "[0, 1]"});
    expectError("1 0 0\n1 -0.1 0\n", {f + ":2:", "'-0.1'", "[0, 1]"});
    expectError("1 0 nan\n", {f + ":1:", "'nan'", "[0, 1]"});
    expectError("1 0 0\n1 0 0\n1 0 0\n1 0 0\n", {f + ":4:", "more colours", "3 points of curve 0"});
    expectError("1 0 0\n1 0 0\n1 0 0\n\n1 0 0\n1 0 0\n\n1 0 0\n",
                {f + ":8:", "curve 2", "2 curves"});
    expectError("1 0 0\n1 0 0\n\n1 0 0\n1 0 0\n", {f + ":1:", "curve 0 has 2 colours", "3 points"});
    expectError("1 0 0\n1 0 0\n1 0 0\n", {f, "curve 1 has 0 colours", "2 points"});
    expectError("", {f, "curve 0 has 0 colours"});
    CurveSet set2 = parseTextCurves("0 0 0\n1 0 0\n", "c.txt");
    writeFileAtomic(path("dye.bcc"), "1 0 0\n1 0 0\n");
    expectInputError([&] { readVertexColours(path("dye.bcc"), &set2); }, {"dye.bcc", ".txt"});
    expectInputError([&] { readVertexColours(path("missing.txt"), &set2); }, {"missing.txt"});
}

}  // namespace
}  // namespace weft::render
