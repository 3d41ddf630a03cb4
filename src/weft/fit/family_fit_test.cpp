#include "weft/fit/family_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "weft/core/test_util.h"
#include "weft/fit/metrics.h"
#include "weft/fit/model_maps.h"
#include "weft/gather/gather_folder.h"

namespace weft {
namespace {

class FamilyFitTest : public testing::TempDirTest {};

// Path-count-weighted mean square difference of two P(T | wi) maps.
double meanSquare(const std::vector<double>& a, const std::vector<double>& b,
                  const std::vector<int64_t>& count) {
    double sum = 0, weight = 0;
    for (size_t i = 0; i < a.size(); ++i)
        sum += count[i] * (a[i] - b[i]) * (a[i] - b[i]), weight += count[i];
    return sum / weight;
}

// A family of yarns whose geometry spans a box from sparse to dense plies:
// the fitted T network, given each yarn's N, rho and alpha, follows that
// yarn's own P(T) far better than the yarns' pooled P(T) does (the mean
// over yarns: no map that ignores the parameters does better), so the
// conditioning reads the parameters, in the right order; and every yarn of
// the box is a valid model.
TEST_F(FamilyFitTest, TransmissionFollowsEachYarnsGeometry) {
    FamilyGatherOptions g;
    g.box.fibers = {50, 600};
    g.box.density = {0.1, 0.4};
    g.points = 6;
    g.pathsPerPoint = testing::scaled(30000);
    g.seed = 3;
    g.threads = 2;
    g.quiet = true;
    gatherFamily(g, path("family"));
    const FamilyGather gather = loadFamilyGather(path("family"));

    FamilyFitOptions o;
    o.config.t.steps = 6000;
    o.config.t.restarts = 2;
    o.config.m.steps = 300;
    o.config.threads = 2;
    o.quiet = true;
    const FamilyFitResult fit = fitFamilyModel(gather, o);
    EXPECT_EQ(fit.model.masking.size(),
              static_cast<size_t>(kMaskingCoefficients * kFamilyMaskingFeatures));

    const size_t yarns = gather.points.size();
    std::vector<GatherCounts> counts;
    std::vector<std::vector<double>> gathered(yarns);
    std::vector<double> pooled(g.bins.incidentCount(), 0.0);
    for (size_t k = 0; k < yarns; ++k) {
        counts.push_back(readGatherCounts(
            readGatherFolder(gather.pointDir(static_cast<int>(k)), GatherFolderKind::Gather)));
        for (size_t i = 0; i < pooled.size(); ++i) {
            gathered[k].push_back(static_cast<double>(counts[k].countT[i]) / counts[k].count[i]);
            pooled[i] += gathered[k][i] / static_cast<double>(yarns);
        }
    }
    double family = 0, ignoringParameters = 0;
    for (size_t k = 0; k < yarns; ++k) {
        const YarnModel yarn = fit.model.at(gather.points[k], "yarn");
        family += meanSquare(transmissionMap(yarn.tNet, g.bins), gathered[k], counts[k].count);
        ignoringParameters += meanSquare(pooled, gathered[k], counts[k].count);
    }
    std::printf("mean square error of P(T): family %.3g, pooled %.3g\n", family / yarns,
                ignoringParameters / yarns);
    EXPECT_LT(family, 0.5 * ignoringParameters);
    // The file round trip of a fitted family.
    saveFamilyModel(fit.model, path("family.json"));
    EXPECT_EQ(familyModelToJson(loadFamilyModel(path("family.json"))),
              familyModelToJson(fit.model));
}

TEST_F(FamilyFitTest, RefusesAnEnergyCalibrationAndABadColourRange) {
    FamilyGatherOptions g;
    g.points = 1;
    g.pathsPerPoint = 200;
    g.threads = 1;
    g.quiet = true;
    gatherFamily(g, path("family"));
    const FamilyGather gather = loadFamilyGather(path("family"));
    FamilyFitOptions o;
    o.config.calibrationDegree = 4;
    testing::expectInputError([&] { fitFamilyModel(gather, o); }, {"energy_calibration_degree"});
    o = {};
    o.functions = 13;
    testing::expectInputError([&] { fitFamilyModel(gather, o); }, {"--colour-functions", "13"});
}

}  // namespace
}  // namespace weft
