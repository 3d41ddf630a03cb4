// The colour-conditioned M network from one any-colour gather, against the
// recoloured RDM and against dedicated fits of single colours.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <vector>

#include "weft/core/test_util.h"
#include "weft/fiber/fiber_test_util.h"
#include "weft/fit/colour_basis.h"
#include "weft/fit/colour_targets.h"
#include "weft/fit/metrics.h"
#include "weft/fit/model_maps.h"
#include "weft/fit/train.h"
#include "weft/gather/colour_paths.h"

namespace weft {
namespace {

GatherOptions anyColourGather(int64_t paths) {
    GatherOptions o;
    o.fiber = testing::table3Fiber("gabardine");
    o.ply = {80, 0.3, 0.12};
    o.paths = paths;
    o.seed = 5;
    o.bins = {4, 12, 8, 16};
    o.anyColour = true;
    o.quiet = true;
    return o;
}

TEST(ColourTargets, MapsEqualTheRecolouredGather) {
    const GatherOptions o = anyColourGather(testing::scaled(20000));
    const GatherSums sums = gatherSums(o);
    const ColourTargets targets(sums.colourPaths, o.bins, sums.count);
    const ColourTargets targetsR(sums.colourPaths, o.bins, sums.count, ColourPath::R);
    // The sparse cell index (a family's) finds the same entries.
    const ColourTargets sparse(sums.colourPaths, o.bins, sums.count, ColourPath::M,
                               ColourTargets::CellIndex::Sparse);
    for (const Rgb colour : {Rgb(0.3, 0.6, 0.9), Rgb(0.999, 0.33, 0.354), o.fiber.cTT}) {
        GatherSums recoloured = sums;
        std::fill(recoloured.sumM.begin(), recoloured.sumM.end(), 0);
        std::fill(recoloured.sumR.begin(), recoloured.sumR.end(), 0);
        std::fill(recoloured.sumTruncated.begin(), recoloured.sumTruncated.end(), 0);
        for (const ColourPath& p : sums.colourPaths)
            addColourPath(recoloured, p, colour, [](int64_t& cell, int64_t v) { cell += v; });
        GatherOptions plain = o;
        plain.fiber.cTT = colour;
        const GatherResult expected = normaliseGather(recoloured, plain);
        for (const auto& [map, truth] : {std::pair{targets.map(colour), &expected.rdmM},
                                         std::pair{sparse.map(colour), &expected.rdmM},
                                         std::pair{targetsR.map(colour), &expected.rdmR}}) {
            ASSERT_EQ(map.size(), truth->size());
            for (size_t k = 0; k < map.size(); ++k)
                ASSERT_NEAR(map[k], (*truth)[k], 1e-5 * (*truth)[k] + 1e-9) << k;
        }
    }
}

TEST(ColourConditionedFit, MatchesDedicatedFitsAtColoursItWasNotShown) {
    const GatherOptions o = anyColourGather(testing::scaled(150000));
    const GatherSums sums = gatherSums(o);
    const ColourTargets targets(sums.colourPaths, o.bins, sums.count);
    const ColourRange range{0.3, 0.999};
    const ColourBasisFit basisFit = fitColourBasis(sums.colourPaths, o.bins, sums.count, range, 4);
    std::printf("basis: %lld rows, truncation error mean %.4f worst %.4f\n",
                static_cast<long long>(basisFit.rows), basisFit.meanError, basisFit.worstError);
    FitConfig config;
    config.m.hidden = {16, 16};
    config.m.steps = testing::scaled(3000);
    config.m.batch = 256;
    config.m.learningRate = 1e-2;
    config.m.finalLearningRate = 1e-3;
    tbb::task_arena arena(2);
    LossCurve curve;
    const NetworkWeights conditioned =
        fitColourConditionedMNetwork(targets, basisFit.basis, config, 7, arena, true, &curve);
    for (const Rgb colour : {Rgb(0.45, 0.62, 0.93), Rgb(0.97, 0.2, 0.5)}) {
        RdmData rdm;
        rdm.dir = "recoloured";
        rdm.bins = o.bins;
        rdm.count = sums.count;
        rdm.rdmM = targets.map(colour);
        const NetworkWeights dedicated =
            fitMultipleScatteringNetwork(rdm, config, 7, arena, true, &curve);
        const double eConditioned = coarseRelativeL2(
            conditionedMultipleScatteringMap(conditioned, basisFit.basis, o.bins, colour), rdm.rdmM,
            o.bins);
        YarnModel dedicatedModel;
        dedicatedModel.mNet = dedicated;
        const double eDedicated =
            coarseRelativeL2(modelMultipleScatteringMap(dedicatedModel, o.bins), rdm.rdmM, o.bins);
        std::printf("C_TT %.2f %.2f %.2f: conditioned %.4f, dedicated %.4f\n", colour.r, colour.g,
                    colour.b, eConditioned, eDedicated);
        EXPECT_LT(eConditioned, 1.3 * eDedicated + 0.02);
    }
}

}  // namespace
}  // namespace weft
