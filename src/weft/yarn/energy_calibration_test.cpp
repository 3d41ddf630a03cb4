#include "weft/yarn/energy_calibration.h"

#include <gtest/gtest.h>

#include <cmath>

#include "weft/core/math.h"
#include "weft/core/rng.h"
#include "weft/core/test_util.h"

namespace weft {
namespace {

// basis() holds x^a y^b z^c at termIndex(a, b, c): checked against std::pow.
TEST(EnergyCalibration, BasisTermsAreTheMonomials) {
    Rng rng(7, 1);
    for (int degree : {0, 1, 3, 6, EnergyCalibration::kMaxDegree}) {
        const double z = rng.uniform(), phi = kTwoPi * rng.uniform();
        const double s = std::sqrt(std::max(0.0, 1 - z * z));
        const Vec3 w{s * std::cos(phi), s * std::sin(phi), z};
        std::vector<double> f(static_cast<size_t>(EnergyCalibration::termCount(degree)));
        EnergyCalibration::basis(w, degree, f.data());
        int terms = 0;
        for (int a = 0; a <= std::min(degree, 1); ++a)
            for (int b = 0; a + b <= degree; ++b)
                for (int c = 0; a + b + c <= degree; ++c, ++terms)
                    EXPECT_DOUBLE_EQ(f[EnergyCalibration::termIndex(a, b, c, degree)],
                                     std::pow(w.x, a) * std::pow(w.y, b) * std::pow(w.z, c));
        EXPECT_EQ(terms, EnergyCalibration::termCount(degree));
    }
}

TEST(EnergyCalibration, EmptyIsOneAndLogScaleIsClamped) {
    EnergyCalibration cal;
    EXPECT_TRUE(cal.empty());
    EXPECT_EQ(cal.scales({0, 0, 1}).r.r, 1.0);
    cal.degree = 0;
    cal.r = {std::vector<double>{10.0}, std::vector<double>{-10.0}, std::vector<double>{0.5}};
    cal.m = {std::vector<double>{0.0}, std::vector<double>{0.0}, std::vector<double>{0.0}};
    const EnergyCalibration::Scales s = cal.scales({0.6, 0, 0.8});
    EXPECT_DOUBLE_EQ(s.r.r, 4.0);
    EXPECT_DOUBLE_EQ(s.r.g, 0.25);
    EXPECT_NEAR(s.r.b, std::exp(0.5), 1e-15);
}

// Node g of a degree-1 calibration (4 terms): coefficient k of channel c is
// g + 10 c + 100 k for R and its negative for M, so that every value names
// its node, channel and term.
EnergyCalibration testNode(int g) {
    EnergyCalibration cal;
    cal.degree = 1;
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < EnergyCalibration::termCount(1); ++k) {
            cal.r[c].push_back(g + 10.0 * c + 100.0 * k);
            cal.m[c].push_back(-(g + 10.0 * c + 100.0 * k));
        }
    return cal;
}

TEST(ColourCalibration, InterpolatesEachChannelInSqrtMinusLogOfItsColour) {
    ColourCalibration byColour;
    byColour.cTT = {0.3, 0.6, 0.999};
    byColour.nodes = {testNode(0), testNode(1), testNode(2)};
    ASSERT_NO_THROW(byColour.validate("test"));
    // Midway between nodes 0 and 1 in u = sqrt(-ln c), by hand.
    const double u0 = std::sqrt(-std::log(0.3)), u1 = std::sqrt(-std::log(0.6));
    const double mid = std::exp(-sqr(0.5 * (u0 + u1)));
    // R at a node, G midway, B beyond the last node (clamped to it).
    const EnergyCalibration cal = byColour.at(Rgb(0.6, mid, 1.0));
    EXPECT_EQ(cal.degree, 1);
    for (int k = 0; k < 4; ++k) {
        EXPECT_NEAR(cal.r[0][k], 1 + 100.0 * k, 1e-12);
        EXPECT_NEAR(cal.r[1][k], 0.5 + 10 + 100.0 * k, 1e-12);
        EXPECT_NEAR(cal.m[1][k], -(0.5 + 10 + 100.0 * k), 1e-12);
        EXPECT_NEAR(cal.r[2][k], 2 + 20 + 100.0 * k, 1e-12);
    }
    // Below the first node: clamped to it.
    EXPECT_NEAR(byColour.at(Rgb(0.05)).r[0][3], 300.0, 1e-12);
    // A single node holds for every colour.
    ColourCalibration one{{0.5}, {testNode(4)}};
    EXPECT_NEAR(one.at(Rgb(0.9)).m[2][1], -(4 + 20 + 100.0), 1e-12);
    EXPECT_TRUE(ColourCalibration{}.at(Rgb(0.5)).empty());
}

TEST(ColourCalibration, ValidateNamesWhatIsWrong) {
    ColourCalibration c{{0.3, 0.3}, {testNode(0), testNode(1)}};
    testing::expectInputError([&] { c.validate("energy_calibration"); },
                              {"energy_calibration.c_tt[1]", "increase strictly"});
    c.cTT = {0.3, 1.2};
    testing::expectInputError([&] { c.validate("x"); }, {"x.c_tt[1]", "(0, 1]"});
    c.cTT = {0.3, 0.5};
    c.nodes[1].degree = 2;
    testing::expectInputError([&] { c.validate("x"); }, {"node 1", "same degree"});
    c.nodes[1] = testNode(1);
    c.nodes[1].m[2].pop_back();
    testing::expectInputError([&] { c.validate("x"); }, {"node 1", "4 coefficients"});
    testing::expectInputError(
        [&] {
            ColourCalibration{{0.5}, {}}.validate("x");
        },
        {"x", "one calibration per node colour", "1 to 64"});
}

}  // namespace
}  // namespace weft
