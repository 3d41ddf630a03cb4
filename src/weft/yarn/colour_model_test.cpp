// Colour-conditioned yarn models: the folded network of one colour against
// the conditioned head, the model file's version 2 form, and the BSDF.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/math.h"
#include "weft/core/rng.h"
#include "weft/core/test_util.h"
#include "weft/yarn/colour_basis.h"
#include "weft/yarn/yarn_bsdf.h"
#include "weft/yarn/yarn_model.h"
#include "weft/yarn/yarn_test_util.h"

namespace weft {
namespace {

// The network's output before its output function, written out plainly.
std::vector<double> rawOutput(const NetworkWeights& net, const std::vector<double>& x) {
    std::vector<double> a = x;
    for (const NetworkLayer& layer : net.layers) {
        std::vector<double> z(layer.out);
        for (int o = 0; o < layer.out; ++o) {
            z[o] = layer.bias[o];
            for (int i = 0; i < layer.in; ++i) z[o] += layer.w(o, i) * a[i];
            if (layer.hasPrelu() && z[o] < 0) z[o] *= layer.prelu[o];
        }
        a = std::move(z);
    }
    return a;
}

// fleece-small with a conditioned m_net of K = 3: block 0 is the model's own
// last layer, blocks 1 and 2 random; a random basis over [0.2, 1].
YarnModel conditionedModel() {
    YarnModel model = loadYarnModel(testing::testModelPath("fleece-small"));
    Rng rng(5, 6);
    NetworkLayer& last = model.mNet.layers.back();
    const NetworkLayer original = last;
    last.out = 9;
    for (int j = 1; j < 3; ++j) {
        for (int k = 0; k < 3 * original.in; ++k)
            last.weight.push_back(static_cast<float>(0.3 * (rng.uniform() - 0.5)));
        for (int c = 0; c < 3; ++c) last.bias.push_back(static_cast<float>(rng.uniform() - 0.5));
    }
    model.mNet.output = OutputFunction::Identity;
    std::vector<std::vector<double>> table(3, std::vector<double>(9, 1.0));
    for (int j = 1; j < 3; ++j)
        for (double& v : table[j]) v = 2 * rng.uniform() - 1;
    model.colour = ColourBasis({0.2, 1.0}, table);
    model.calibration = {};
    return model;
}

TEST(ColourModel, FoldedNetworkEqualsTheConditionedHead) {
    const YarnModel model = conditionedModel();
    ASSERT_NO_THROW(model.validate());
    Rng rng(1, 2);
    for (const Rgb colour : {Rgb(0.25, 0.5, 0.99), Rgb(0.6, 0.6, 0.6), Rgb(0.2, 1.0, 0.3)}) {
        const YarnModel one = model.forColour(colour, "test");
        EXPECT_EQ(one.fiber.cTT, colour);
        EXPECT_FALSE(one.colour.has_value());
        EXPECT_EQ(one.mNet.outputs(), 3);
        EXPECT_EQ(one.mNet.output, OutputFunction::Exp);
        ASSERT_NO_THROW(one.validate());
        for (int n = 0; n < 20; ++n) {
            std::vector<double> x(6);
            for (double& v : x) v = 2 * rng.uniform() - 1;
            const std::vector<double> coefficients = rawOutput(model.mNet, x);
            const std::vector<float> a(coefficients.begin(), coefficients.end());
            const Rgb head = conditionedM(a.data(), *model.colour, colour);
            const std::vector<double> folded = rawOutput(one.mNet, x);
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(std::exp(folded[c]), head[c], 1e-5 * head[c]) << c;
        }
    }
}

TEST(ColourModel, FileFormIsVersionTwoAndOldFilesStillLoad) {
    const YarnModel model = conditionedModel();
    const nlohmann::json j = yarnModelToJson(model);
    EXPECT_EQ(j.at("version"), 2);
    const YarnModel back = yarnModelFromJson(j, "model.json");
    ASSERT_TRUE(back.colour.has_value());
    EXPECT_EQ(back.colour->table(), model.colour->table());
    EXPECT_EQ(back.mNet, model.mNet);
    // An ordinary model is still written as version 1, and read.
    const YarnModel plain = loadYarnModel(testing::testModelPath("fleece-small"));
    EXPECT_EQ(yarnModelToJson(plain).at("version"), 1);
    // "colour" needs version 2; m_net must match the number of functions.
    nlohmann::json old = j;
    old["version"] = 1;
    testing::expectInputError([&] { yarnModelFromJson(old, "model.json"); }, {"colour"});
    nlohmann::json wrong = j;
    wrong["colour"]["functions"].erase(2);
    testing::expectInputError([&] { yarnModelFromJson(wrong, "model.json"); }, {"m_net"});
    nlohmann::json future = j;
    future["version"] = 6;
    testing::expectInputError([&] { yarnModelFromJson(future, "model.json"); },
                              {"unsupported version 6", "1 to 5"});
    testing::expectInputError([&] { plain.forColour(Rgb(0.5), "scene.json: yarns[0]"); },
                              {"scene.json: yarns[0]", "fitted for one colour", "--colour-range"});
    testing::expectInputError([&] { model.forColour(Rgb(0.5, 1.5, 0.5), "x"); },
                              {"x: C_TT 1.5", "colour range [0.2, 1]", "appearance"});
    // Below the range too: no silent clamp to its end (issue 42).
    testing::expectInputError([&] { model.forColour(Rgb(0.5, 0.1, 0.5), "x"); },
                              {"x: C_TT 0.1", "colour range [0.2, 1]"});
}

// A calibration by colour of two nodes for the conditioned model: node g
// scales R by e^(0.1 (g + 1)) and M by e^(-0.1 (g + 1)) everywhere (constant term).
ColourCalibration twoNodeCalibration() {
    ColourCalibration byColour;
    byColour.cTT = {0.3, 0.9};
    for (int g = 0; g < 2; ++g) {
        EnergyCalibration node;
        node.degree = 1;
        for (int c = 0; c < 3; ++c) {
            node.r[c] = {0.1 * (g + 1), 0, 0, 0};
            node.m[c] = {-0.1 * (g + 1), 0, 0, 0};
        }
        byColour.nodes.push_back(node);
    }
    return byColour;
}

TEST(ColourModel, CalibrationByColourIsVersionThreeAndFollowsTheColour) {
    YarnModel model = conditionedModel();
    model.colourCalibration = twoNodeCalibration();
    ASSERT_NO_THROW(model.validate());
    const nlohmann::json j = yarnModelToJson(model);
    EXPECT_EQ(j.at("version"), 3);
    EXPECT_EQ(j.at("energy_calibration").at("form"), "log-polynomial-sphere-by-c-tt");
    const YarnModel back = yarnModelFromJson(j, "model.json");
    ASSERT_EQ(back.colourCalibration.cTT, model.colourCalibration.cTT);
    EXPECT_EQ(back.colourCalibration.nodes[1].m[2], model.colourCalibration.nodes[1].m[2]);
    // forColour: the red channel at the first node, green at the second, blue between.
    const double u0 = std::sqrt(-std::log(0.3)), u1 = std::sqrt(-std::log(0.9));
    const double blue = std::exp(-sqr(0.25 * u0 + 0.75 * u1));  // 3/4 of the way to node 1
    const YarnModel one = model.forColour(Rgb(0.3, 0.9, blue), "test");
    EXPECT_TRUE(one.colourCalibration.empty());
    const EnergyCalibration::Scales s = one.calibration.scales(Vec3{0, 0, 1});
    EXPECT_NEAR(s.r.r, std::exp(0.1), 1e-12);
    EXPECT_NEAR(s.m.g, std::exp(-0.2), 1e-12);
    EXPECT_NEAR(s.r.b, std::exp(0.175), 1e-12);
    // What a file may not say: the by-colour form before version 3 or for a
    // model of one colour; node colours out of order.
    nlohmann::json two = j;
    two["version"] = 2;
    testing::expectInputError([&] { yarnModelFromJson(two, "model.json"); },
                              {"model.json", "energy_calibration", "c_tt"});
    nlohmann::json unordered = j;
    unordered["energy_calibration"]["c_tt"] = {0.9, 0.3};
    testing::expectInputError([&] { yarnModelFromJson(unordered, "model.json"); },
                              {"model.json", "c_tt[1]", "increase strictly"});
    YarnModel plain = loadYarnModel(testing::testModelPath("fleece-small"));
    plain.colourCalibration = twoNodeCalibration();
    testing::expectInputError([&] { plain.validate(); }, {"only a conditioned model"});
}

TEST(ColourModel, BsdfOfAConditionedModelIsThatOfItsOwnColour) {
    const YarnModel model = conditionedModel();
    const YarnBsdf conditioned(model, "conditioned");
    const YarnBsdf own(model.forColour(model.fiber.cTT, "test"), "own");
    const YarnBsdf other(model.forColour(Rgb(0.3, 0.3, 0.3), "test"), "other");
    Rng rng(3, 3);
    double differs = 0;
    for (int n = 0; n < 50; ++n) {
        const Vec3 wi = normalize(Vec3{rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform()});
        const Vec3 wo =
            normalize(Vec3{rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5});
        EXPECT_EQ(conditioned.eval(wi, wo), own.eval(wi, wo));
        differs += std::abs(other.eval(wi, wo).g - own.eval(wi, wo).g);
    }
    EXPECT_GT(differs, 0);
}

}  // namespace
}  // namespace weft
