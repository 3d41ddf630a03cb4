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

// Path-count-weighted mean square difference of a map from a yarn's
// gathered P(T | wi), less the gathered values' own variance (binomial,
// g (1 - g) / (n - 1) per bin): an unbiased estimate of the map's squared
// error against the yarn's true P(T).
double meanSquareBias(const std::vector<double>& map, const std::vector<double>& gathered,
                      const std::vector<int64_t>& count) {
    double sum = 0, weight = 0;
    for (size_t i = 0; i < map.size(); ++i) {
        if (count[i] < 2) continue;
        const double g = gathered[i], n = static_cast<double>(count[i]);
        sum += n * ((map[i] - g) * (map[i] - g) - g * (1 - g) / (n - 1));
        weight += n;
    }
    return sum / weight;
}

// A family of yarns whose geometry spans a box from sparse to dense plies:
// the fitted T network, given each yarn's N, rho and alpha, follows that
// yarn's own P(T) far better than the yarns' pooled P(T) does (the mean
// over yarns: no map that ignores the parameters does better; both errors
// less the gathered values' own noise), so the
// conditioning reads the parameters, in the right order; and every yarn of
// the box is a valid model.
TEST_F(FamilyFitTest, TransmissionFollowsEachYarnsGeometry) {
    FamilyGatherOptions g;
    g.box.fibers = {50, 600};
    g.box.density = {0.1, 0.4};
    g.points = 6;
    g.pathsPerPoint = 30000;  // not scaled: fewer paths would leave only the noise to compare
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
    o.config.calibrationDegree = -1;  // family_calibration_test checks it
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
            // A bin without paths (few paths under the sanitizers) weighs nothing.
            const int64_t count = counts[k].count[i];
            gathered[k].push_back(count > 0 ? static_cast<double>(counts[k].countT[i]) / count
                                            : 0.0);
            pooled[i] += gathered[k][i] / static_cast<double>(yarns);
        }
    }
    double family = 0, ignoringParameters = 0;
    for (size_t k = 0; k < yarns; ++k) {
        const YarnModel yarn = fit.model.at(gather.points[k], "yarn");
        family += meanSquareBias(transmissionMap(yarn.tNet, g.bins), gathered[k], counts[k].count);
        ignoringParameters += meanSquareBias(pooled, gathered[k], counts[k].count);
    }
    std::printf("squared error of P(T) beyond the noise: family %.3g, pooled %.3g\n",
                family / yarns, ignoringParameters / yarns);
    EXPECT_LT(family, 0.5 * ignoringParameters);
    // The file round trip of a fitted family.
    saveFamilyModel(fit.model, path("family.json"));
    EXPECT_EQ(familyModelToJson(loadFamilyModel(path("family.json"))),
              familyModelToJson(fit.model));
}

TEST_F(FamilyFitTest, RefusesBadColourFunctions) {
    FamilyGatherOptions g;
    g.points = 1;
    g.pathsPerPoint = 200;
    g.threads = 1;
    g.quiet = true;
    gatherFamily(g, path("family"));
    const FamilyGather gather = loadFamilyGather(path("family"));
    FamilyFitOptions o;
    o.functions = 13;
    testing::expectInputError([&] { fitFamilyModel(gather, o); }, {"--colour-functions", "13"});
}

}  // namespace
}  // namespace weft
