// The colour functions of a conditioned M model: interpolation in s, the
// file form, and the head that turns coefficients into M.
#include "weft/yarn/colour_basis.h"

#include <gtest/gtest.h>

#include <cmath>

#include "weft/core/error.h"
#include "weft/core/test_util.h"

namespace weft {
namespace {

TEST(ColourBasis, InterpolatesLinearlyInSAndClampsToTheRange) {
    const ColourRange range{0.25, 1.0};
    // Nodes at s = 0, ln 2, 2 ln 2 (C_TT = 1, 0.5, 0.25).
    const ColourBasis basis(range, {{1, 1, 1}, {0, 2, 6}});
    EXPECT_NEAR(basis.nodeS(1), std::log(2.0), 1e-15);
    double phi[2];
    basis.eval(0.5, phi);
    EXPECT_EQ(phi[0], 1.0);
    EXPECT_NEAR(phi[1], 2.0, 1e-12);
    // Halfway in s between C_TT = 0.5 and 0.25: C_TT = 0.5 / sqrt(2).
    basis.eval(0.5 / std::sqrt(2.0), phi);
    EXPECT_NEAR(phi[1], 4.0, 1e-12);
    basis.eval(0.1, phi);  // below the range: its end
    EXPECT_NEAR(phi[1], 6.0, 1e-12);
    basis.eval(1.0, phi);
    EXPECT_NEAR(phi[1], 0.0, 1e-12);

    const ColourBasis back = ColourBasis::fromJson(basis.toJson(), "model.json");
    EXPECT_EQ(back.table(), basis.table());
    EXPECT_EQ(back.range().lo, 0.25);
    testing::expectInputError([&] { ColourBasis(range, {{1, 2, 1}}); }, {"constant 1"});
    testing::expectInputError([&] { ColourBasis(range, {{1, 1}, {1, 1, 1}}); }, {"function 1"});
    testing::expectInputError([] { ColourBasis({0.5, 0.4}, {{1, 1}}); }, {"0 < LO < HI <= 1"});
    nlohmann::json bad = basis.toJson();
    bad["functions"][1][2] = "x";
    testing::expectInputError([&] { ColourBasis::fromJson(bad, "model.json"); },
                              {"model.json", "non-number"});
}

TEST(ColourBasis, ConditionedMIsExpOfTheCoefficientsAgainstTheBasisPerChannel) {
    // phi_1 = s exactly (nodes at s = 0 .. ln 4): M_c = exp(a_0c + a_1c s_c),
    // i.e. e^a_0c C_TT,c^(-a_1c), a power law in the colour.
    const double s4 = std::log(4.0);
    const ColourBasis basis({0.25, 1.0}, {{1, 1, 1, 1, 1}, {0, s4 / 4, s4 / 2, 3 * s4 / 4, s4}});
    const float a[6] = {0.5f, -1.0f, 0.0f, -2.0f, -3.0f, -1.0f};  // a_0 (r, g, b), a_1 (r, g, b)
    const Rgb colour(0.5, 0.8, 1.0);
    const Rgb m = conditionedM(a, basis, colour);
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(m[c], std::exp(a[c]) * std::pow(colour[c], -a[3 + c]), 1e-6 * m[c]) << c;
}

}  // namespace
}  // namespace weft
