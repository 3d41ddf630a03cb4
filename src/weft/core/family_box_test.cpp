#include "weft/core/family_box.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "weft/core/math.h"
#include "weft/core/test_util.h"

namespace weft {
namespace {

using testing::expectInputError;

// Fleece (paper Table 3): inside the default box.
YarnPoint fleece() { return {300, 0.30, 0.24, 7.238, 10.000, 25.989, Rgb(0.040, 0.087, 0.087)}; }

TEST(FamilyBox, ChecksNameTheFieldTheValueAndTheRange) {
    const FamilyBox box;
    YarnPoint p = fleece();
    p.twist = 0.5;
    expectInputError([&] { box.check(p, "scene.json: yarns[2].yarn"); },
                     {"scene.json: yarns[2].yarn", "twist", "0.5", "[0, 0.3]"});
    p = fleece();
    p.cR.b = 1.5;
    expectInputError([&] { box.check(p, "yarn"); }, {"c_r[2]", "1.5", "[0, 1]"});
    p = fleece();
    p.fibers = 100;
    expectInputError([&] { box.check(p, "yarn"); }, {"fibers", "100", "[200, 600]"});
}

TEST(FamilyBox, NormalisedInputsMapEachRangeOntoMinusOneToOne) {
    FamilyBox box;
    box.twist = {0.1, 0.1};  // zero width: input 0
    const YarnPoint lo = box.at({0, 0, 0, 0, 0, 0, 0, 0, 0});
    YarnPoint hi = lo;
    hi.fibers = 600, hi.density = 0.4, hi.betaRDeg = 8, hi.betaTTDeg = 28, hi.gammaTTDeg = 39;
    hi.cR = Rgb(1, 0.5, 0);
    const auto qLo = box.normalised(lo), qHi = box.normalised(hi);
    for (int d = 0; d < 6; ++d) EXPECT_EQ(qLo[d], d == 2 ? 0.0 : -1.0) << d;
    for (int d = 0; d < 6; ++d) EXPECT_EQ(qHi[d], d == 2 ? 0.0 : 1.0) << d;
    EXPECT_EQ(qHi[6], 1.0);
    EXPECT_EQ(qHi[7], 0.0);
    EXPECT_EQ(qHi[8], -1.0);
    // Fleece's N = 300 is a quarter of the way through [200, 600].
    EXPECT_DOUBLE_EQ(FamilyBox{}.normalised(fleece())[0], -0.5);
}

TEST(FamilyBox, JsonRoundTripAndStrictReading) {
    FamilyBox box;
    box.twist = {0.1, 0.2};
    box.cR = {0.3, 0.3};
    const FamilyBox back = FamilyBox::fromJson(box.toJson(), "box.json");
    EXPECT_EQ(back.toJson(), box.toJson());
    nlohmann::json j = box.toJson();
    j["density"] = {0.4, 0.2};
    expectInputError([&] { FamilyBox::fromJson(j, "box.json"); },
                     {"box.json", "density", "lo <= hi"});
    j = box.toJson();
    j["fibers"] = {200.5, 300};
    expectInputError([&] { FamilyBox::fromJson(j, "box.json"); }, {"fibers", "whole numbers"});
    j = box.toJson();
    j["beta_r_deg"] = {1, NAN};
    expectInputError([&] { FamilyBox::fromJson(j, "box.json"); }, {"box.json", "beta_r_deg"});
    j = box.toJson();
    j["colour"] = {0, 1};
    expectInputError([&] { FamilyBox::fromJson(j, "box.json"); }, {"colour"});
    j = box.toJson();
    j.erase("twist");
    expectInputError([&] { FamilyBox::fromJson(j, "box.json"); }, {"twist"});
    j = box.toJson();
    j["twist"] = {0.1};
    expectInputError([&] { FamilyBox::fromJson(j, "box.json"); }, {"twist", "[lo, hi]"});
}

// The points are spread like a low-discrepancy set, not like random ones: in
// the base-3 dimension (density) 81 points fall one per stratum of 1/81 but
// for the one point Halton index 81 moves (81 random points leave about 30
// strata empty); every point lies in the box, and another seed moves them.
TEST(FamilyPoints, SpreadOverTheBoxAndDependOnTheSeed) {
    const FamilyBox box;
    const std::vector<YarnPoint> points = familyPoints(box, 81, 7);
    std::vector<int> perStratum(81, 0);
    for (const YarnPoint& p : points) {
        EXPECT_NO_THROW(box.check(p, "point"));
        const double u = (p.density - box.density.lo) / (box.density.hi - box.density.lo);
        ++perStratum[std::min(80, static_cast<int>(u * 81))];
    }
    int empty = 0;
    for (int n : perStratum) {
        EXPECT_LE(n, 2);
        empty += n == 0;
    }
    EXPECT_LE(empty, 1);
    EXPECT_EQ(familyPoints(box, 81, 7), points);
    EXPECT_NE(familyPoints(box, 81, 8), points);
    // The C_R channels are separate dimensions.
    EXPECT_NE(points[3].cR.r, points[3].cR.g);
}

// The edges design follows the arcsine law in every dimension: u = (1 -
// cos(pi v)) / 2 of the uniform v, so P(u < x) = (2 / pi) asin(sqrt(x)).
// With 81 points, a stratum of v (1/81 each, one point per stratum in the
// base-3 dimension) maps to [F^-1(k/81), F^-1((k+1)/81)) of u: each holds
// about one point, and the 5% next to each face about 14% of them (uniform: 5%).
TEST(FamilyPoints, EdgesDesignCrowdsTheFaces) {
    const FamilyBox box;
    const std::vector<YarnPoint> points = familyPoints(box, 81, 7, FamilyDesign::Edges);
    std::vector<int> perStratum(81, 0);
    int nearFaces = 0;
    for (const YarnPoint& p : points) {
        EXPECT_NO_THROW(box.check(p, "point"));
        const double u = (p.density - box.density.lo) / (box.density.hi - box.density.lo);
        const double v = 2 / kPi * std::asin(std::sqrt(std::clamp(u, 0.0, 1.0)));  // F(u)
        ++perStratum[std::min(80, static_cast<int>(v * 81))];
        nearFaces += u < 0.05 || u > 0.95;
    }
    int empty = 0;
    for (int n : perStratum) {
        EXPECT_LE(n, 2);
        empty += n == 0;
    }
    EXPECT_LE(empty, 1);
    // 2 F(0.05) = 0.287 of 81 points: 23.
    EXPECT_NEAR(nearFaces, 23, 2);
    EXPECT_EQ(parseFamilyDesign("edges", "--design"), FamilyDesign::Edges);
    EXPECT_STREQ(familyDesignName(FamilyDesign::Halton), "halton");
    testing::expectInputError([] { parseFamilyDesign("grid", "--design"); },
                              {"--design", "grid", "halton, edges"});
}

}  // namespace
}  // namespace weft
