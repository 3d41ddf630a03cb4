#include "weft/yarn/family_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "weft/core/chi2.h"
#include "weft/core/json_file.h"
#include "weft/core/math.h"
#include "weft/core/test_util.h"
#include "weft/yarn/material_preset.h"
#include "weft/yarn/yarn_bsdf.h"
#include "weft/yarn/yarn_integrals.h"
#include "weft/yarn/yarn_test_util.h"

namespace weft {
namespace {

using testing::expectInputError;

// A family of random networks (the trainer's initialisation) and a masking
// term with every coefficient set.
FamilyModel syntheticFamily() {
    FamilyModel f;
    f.tNet = NetworkWeights::initialised({kFamilyTInputs, 7, 7, 1}, OutputFunction::Sigmoid, 1);
    f.mNet =
        NetworkWeights::initialised({kFamilyMInputs, 8, 8, 3 * 3}, OutputFunction::Identity, 2);
    f.colour = ColourBasis({0.3, 0.999}, {{1, 1, 1}, {-1, 0, 1}, {1, -1, 0.5}});
    for (int k = 0; k < kMaskingCoefficients * kFamilyMaskingFeatures; ++k)
        f.masking.push_back(0.01 * (k + 1) * (k % 2 ? -1 : 1));
    f.masking[0] = 0.6;  // the constant term of c0
    // A calibration of degree 1 with every coefficient set, small.
    FamilyCalibration& cal = f.calibration;
    cal.degree = 1;
    cal.cTT = {0.3, 0.6, 0.999};
    const int size = EnergyCalibration::termCount(1) * kFamilyCalibrationFeatures;
    for (int k = 0; k < size; ++k) cal.r.push_back(0.003 * (k % 5) - 0.005);
    for (size_t g = 0; g < cal.cTT.size(); ++g) {
        cal.m.emplace_back();
        for (int k = 0; k < size; ++k) cal.m.back().push_back(0.002 * ((k + g) % 7) - 0.006);
    }
    f.fit = {{"note", "synthetic"}};
    f.validate();
    return f;
}

// The network's output in double, written out here (y = W x + b, PReLU,
// output function), independently of FixedMlp and the trainer's Mlp.
std::vector<double> forward(const NetworkWeights& net, std::vector<double> x) {
    for (const NetworkLayer& layer : net.layers) {
        std::vector<double> y(layer.out);
        for (int o = 0; o < layer.out; ++o) {
            double z = layer.bias[o];
            for (int j = 0; j < layer.in; ++j) z += static_cast<double>(layer.w(o, j)) * x[j];
            if (layer.hasPrelu() && z < 0) z *= layer.prelu[o];
            y[o] = z;
        }
        x = std::move(y);
    }
    for (double& v : x)
        v = net.output == OutputFunction::Sigmoid ? 1 / (1 + std::exp(-v))
            : net.output == OutputFunction::Exp   ? std::exp(v)
                                                  : v;
    return x;
}

YarnPoint fleece() { return yarnPointOf(findMaterialPreset("fleece")); }

class FamilyModelFile : public testing::TempDirTest {};

TEST_F(FamilyModelFile, RoundTripIsExact) {
    const FamilyModel f = syntheticFamily();
    const std::string path = this->path("family.json");
    saveFamilyModel(f, path);
    const FamilyModel g = loadFamilyModel(path);
    EXPECT_EQ(g.tNet, f.tNet);
    EXPECT_EQ(g.mNet, f.mNet);
    EXPECT_EQ(g.masking, f.masking);
    EXPECT_EQ(g.calibration.degree, f.calibration.degree);
    EXPECT_EQ(g.calibration.cTT, f.calibration.cTT);
    EXPECT_EQ(g.calibration.r, f.calibration.r);
    EXPECT_EQ(g.calibration.m, f.calibration.m);
    EXPECT_EQ(g.box.toJson(), f.box.toJson());
    EXPECT_EQ(g.colour.toJson(), f.colour.toJson());
    EXPECT_EQ(g.fit, f.fit);
    EXPECT_EQ(familyModelToJson(g), familyModelToJson(f));
    // Version 2 holds the calibration; without one the file stays version 1.
    EXPECT_EQ(familyModelToJson(f).at("version"), 2);
    FamilyModel none = f;
    none.calibration = {};
    EXPECT_EQ(familyModelToJson(none).at("version"), 1);
    EXPECT_FALSE(familyModelToJson(none).contains("energy_calibration"));
}

// The yarn's calibration by colour is linear in its features: with hand-set
// coefficients, log s_R = 0.5 q_N - 0.3 q_CR,c and, at the node colour 0.6,
// log s_M = 0.2 + 0.2 z q_alpha, where fleece (N 300, alpha 0.24, C_R 0.04,
// 0.087, 0.087) in the box N [200, 600], alpha [0, 0.3], C_R [0, 1] has
// q_N = -0.5, q_alpha = 0.6, q_CR = 2 C_R - 1.
TEST(FamilyModel, CalibrationIsLinearInTheYarnsFeatures) {
    FamilyModel f = syntheticFamily();
    FamilyCalibration& cal = f.calibration;
    const int z = EnergyCalibration::termIndex(0, 0, 1, 1);
    for (double& v : cal.r) v = 0;
    for (auto& block : cal.m)
        for (double& v : block) v = 0;
    cal.r[0 * kFamilyCalibrationFeatures + 1] = 0.5;
    cal.r[0 * kFamilyCalibrationFeatures + 7] = -0.3;
    cal.m[1][0 * kFamilyCalibrationFeatures + 0] = 0.2;
    cal.m[1][z * kFamilyCalibrationFeatures + 3] = 0.2;
    cal.m[0][0] = 1.0;  // other nodes: not used at C_TT 0.6
    cal.m[2][0] = -1.0;
    const YarnModel yarn = f.at(fleece(), "yarn").forColour(Rgb(0.6), "yarn");
    const Vec3 wi = normalize(Vec3(0.3, -0.2, 0.8));
    const EnergyCalibration::Scales s = yarn.calibration.scales(wi);
    const Rgb qCR(2 * 0.04 - 1, 2 * 0.087 - 1, 2 * 0.087 - 1);
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(s.r[c], std::exp(0.5 * -0.5 - 0.3 * qCR[c]), 1e-12);
        EXPECT_NEAR(s.m[c], std::exp(0.2 + 0.2 * wi.z * 0.6), 1e-12);
    }
}

TEST(FamilyModel, AYarnIsTheFamilyWithItsParametersAsConstantInputs) {
    const FamilyModel f = syntheticFamily();
    for (const YarnPoint& p : {fleece(), yarnPointOf(findMaterialPreset("cotton")), f.centre()}) {
        const YarnModel m = f.at(p, "yarn");
        const auto q = f.box.normalised(p);
        EXPECT_EQ(m.ply.fibers, p.fibers);
        EXPECT_EQ(m.fiber.betaRDeg, p.betaRDeg);
        EXPECT_EQ(m.fiber.cR, p.cR);
        // Eq. 8's tilt follows the twist: atan(pi alpha).
        EXPECT_NEAR(m.rLobe.tiltDeg, degrees(std::atan(kPi * p.twist)), 1e-12);
        Rng rng(3, 4);
        for (int trial = 0; trial < 20; ++trial) {
            std::vector<double> dirs(6);
            for (double& v : dirs) v = 2 * rng.uniform() - 1;
            std::vector<double> tIn(dirs.begin(), dirs.begin() + 3), mIn = dirs;
            for (int d = 0; d < 3; ++d) tIn.push_back(q[d]);
            for (double v : q) mIn.push_back(v);
            const double tFull = forward(f.tNet, tIn)[0];
            const double tYarn = forward(m.tNet, {dirs[0], dirs[1], dirs[2]})[0];
            EXPECT_NEAR(tYarn, tFull, 1e-6);
            const std::vector<double> mFull = forward(f.mNet, mIn), mYarn = forward(m.mNet, dirs);
            for (size_t k = 0; k < mFull.size(); ++k) EXPECT_NEAR(mYarn[k], mFull[k], 1e-5);
        }
        // The masking coefficients are linear in (1, q_N, ..., q_gammaTT).
        ASSERT_EQ(m.rLobe.masking.size(), static_cast<size_t>(kMaskingCoefficients));
        for (int k = 0; k < kMaskingCoefficients; ++k) {
            double c = f.masking[k * kFamilyMaskingFeatures];
            for (int l = 1; l < kFamilyMaskingFeatures; ++l)
                c += f.masking[k * kFamilyMaskingFeatures + l] * q[l - 1];
            EXPECT_NEAR(m.rLobe.masking[k], c, 1e-12);
        }
    }
}

TEST(FamilyModel, RefusesAYarnOutsideItsBoxAndDamagedFiles) {
    const FamilyModel f = syntheticFamily();
    YarnPoint p = fleece();
    p.density = 0.5;
    expectInputError([&] { f.at(p, "scene.json: yarns[0].yarn"); },
                     {"scene.json: yarns[0].yarn", "density", "0.5", "[0.2, 0.4]"});
    p = fleece();
    p.gammaTTDeg = 45;
    expectInputError([&] { f.at(p, "--yarn"); }, {"gamma_tt_deg", "45", "[19, 39]"});

    const nlohmann::json good = familyModelToJson(f);
    nlohmann::json j = good;
    j["version"] = 3;
    expectInputError([&] { familyModelFromJson(j, "f.json"); }, {"f.json", "version", "3"});
    j = good;
    j["version"] = 1;  // version 1 has no calibration
    expectInputError([&] { familyModelFromJson(j, "f.json"); }, {"f.json", "energy_calibration"});
    j = good;
    j["energy_calibration"]["m"][1].erase(0);
    expectInputError([&] { familyModelFromJson(j, "f.json"); },
                     {"f.json", "energy_calibration.m[1]", "4 rows of 8"});
    j = good;
    j["energy_calibration"]["c_tt"] = {0.3, 0.2, 0.999};
    expectInputError([&] { familyModelFromJson(j, "f.json"); },
                     {"f.json", "energy_calibration.c_tt[1]", "increase"});
    j = good;
    j["energy_calibration"]["r"][0][7] = "x";
    expectInputError([&] { familyModelFromJson(j, "f.json"); },
                     {"f.json", "energy_calibration.r[0][7]"});
    j = good;
    j["t_net"]["layers"][0]["weight"][0].erase(0);  // 5 inputs
    expectInputError([&] { familyModelFromJson(j, "f.json"); }, {"f.json", "t_net", "6 numbers"});
    j = good;
    j["box"]["twist"] = {0.3, 0.1};
    expectInputError([&] { familyModelFromJson(j, "f.json"); }, {"f.json", "twist", "lo <= hi"});
    j = good;
    j["r_lobe"]["masking"]["coefficients"][3] = {1, 2};
    expectInputError([&] { familyModelFromJson(j, "f.json"); },
                     {"r_lobe.masking.coefficients[3]", "4 rows of 7"});
    j = good;
    j["extra"] = 1;
    expectInputError([&] { familyModelFromJson(j, "f.json"); }, {"extra"});
    // An ordinary model is not a family model, and says which it is.
    EXPECT_TRUE(isFamilyModelDocument(good));
    EXPECT_FALSE(isFamilyModelDocument(yarnModelToJson(f.at(fleece(), "yarn"))));
    expectInputError(
        [&] { familyModelFromJson(yarnModelToJson(f.at(fleece(), "yarn")), "m.json"); },
        {"m.json", "format", "weft-family-model"});
}

// The shipped family model (models/family.json, docs/family.md): at three
// yarns of its box, the tabulated sampler draws its own pdf (chi-square),
// and the pdf integrates to 1 - P_T.
TEST(FamilyModel, ShippedFamilySamplesItsPdfAtThreeYarns) {
    const FamilyModel family =
        loadFamilyModel(std::string(WEFT_SOURCE_DIR) + "/models/family.json");
    YarnPoint low = family.box.at({0.1, 0.9, 0.05, 0.2, 0.1, 0.3, 0.8, 0.5, 0.2});
    YarnPoint high = family.box.at({0.9, 0.15, 0.95, 0.9, 0.85, 0.7, 0.1, 0.4, 0.9});
    const std::vector<YarnPoint> yarns = testing::sampleScale() < 1
                                             ? std::vector<YarnPoint>{high}
                                             : std::vector<YarnPoint>{fleece(), low, high};
    const std::vector<Vec3> incident = {sphericalDirection(radians(20.0), radians(40.0)),
                                        sphericalDirection(radians(75.0), radians(-100.0))};
    const double alpha =
        sidakCorrectedLevel(0.01, static_cast<int>(yarns.size() * incident.size()));
    const SphereGrid grid{180, 60};
    for (const YarnPoint& p : yarns) {
        const YarnBsdf bsdf(family.at(p, "yarn").forColour(Rgb(0.7, 0.5, 0.9), "test"));
        for (const Vec3& wi : incident) {
            const Chi2Result r =
                testing::yarnSamplingChi2(bsdf, wi, grid, testing::scaled(100000), 11, true);
            const SphereRule rule = yarnSphereRule(bsdf, wi, 2);
            double pdfIntegral = 0;
            for (size_t k = 0; k < rule.directions.size(); ++k)
                pdfIntegral += bsdf.pdf(wi, rule.directions[k]) * rule.weights[k];
            EXPECT_NEAR(pdfIntegral, 1 - bsdf.lobeProbabilities(wi).t, 4e-3)
                << p.toJson() << " " << wi;
            EXPECT_GT(r.pValue, alpha) << p.toJson() << " " << wi;
            std::printf("yarn %s, wi %g %g %g: chi2 %.1f, dof %d, p %.3g\n",
                        p.toJson().dump().c_str(), wi.x, wi.y, wi.z, r.statistic, r.dof, r.pValue);
        }
    }
}

}  // namespace
}  // namespace weft
