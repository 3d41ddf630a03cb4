// The colour basis of a conditioned M model: interpolation, its file form,
// and the fit against records whose colour dependence is known exactly.
#include "weft/fit/colour_basis.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/rng.h"
#include "weft/core/test_util.h"

namespace weft {
namespace {

const RdmBins kBins{2, 4, 4, 8};

// `perCell` M paths in every cell, with TT counts from tt(rng, cell).
template <typename TT>
std::vector<ColourPath> syntheticPaths(int perCell, TT&& tt) {
    std::vector<ColourPath> paths;
    Rng rng(3, 4);
    for (size_t i = 0; i < kBins.incidentCount(); ++i)
        for (size_t o = 0; o < kBins.outgoingCount(); ++o)
            for (int n = 0; n < perCell; ++n) {
                ColourPath p;
                p.kind = ColourPath::M;
                p.incidentBin = static_cast<int32_t>(i);
                p.outgoingBin = static_cast<int32_t>(o);
                p.ttEvents = tt(rng, i * kBins.outgoingCount() + o);
                for (int c = 0; c < 3; ++c) p.weight[c] = static_cast<float>(0.2 + rng.uniform());
                paths.push_back(p);
            }
    return paths;
}

std::vector<int64_t> counts() { return std::vector<int64_t>(kBins.incidentCount(), 1000); }

TEST(ColourBasisFit, CellsOfOneTTCountNeedTwoFunctions) {
    // A cell whose paths all have k TT events: log V = const - k s, affine in
    // s, so the basis {1, phi_1} represents every cell exactly and phi_1 is
    // affine in s.
    const auto paths =
        syntheticPaths(6, [](Rng&, size_t cell) { return static_cast<int>(cell % 7); });
    const ColourBasisFit fit = fitColourBasis(paths, kBins, counts(), {0.3, 0.999}, 2, 17);
    EXPECT_LT(fit.worstError, 1e-10);
    const auto& phi = fit.basis.table()[1];
    for (size_t g = 1; g + 1 < phi.size(); ++g)
        EXPECT_NEAR(phi[g - 1] - 2 * phi[g] + phi[g + 1], 0.0, 1e-9) << g;
    EXPECT_GT(phi.front(), phi.back());  // the sign convention
    EXPECT_EQ(fit.rows, static_cast<int64_t>(kBins.incidentCount() * kBins.outgoingCount() * 3));
}

TEST(ColourBasisFit, MixedTTCountsNeedMoreFunctionsAndTheErrorFalls) {
    // Each cell mixes short (k = 1) and long (k = 15 .. 40) paths in its own
    // proportion: log V is curved in s, and no basis of two functions fits it.
    const auto paths = syntheticPaths(12, [](Rng& rng, size_t cell) {
        return rng.uniform() < 0.2 + 0.6 * ((cell * 7919) % 97) / 97.0
                   ? 1
                   : 15 + static_cast<int>(cell % 26);
    });
    double previous = 1e9;
    for (int k = 2; k <= 6; ++k) {
        const ColourBasisFit fit = fitColourBasis(paths, kBins, counts(), {0.3, 0.999}, k);
        std::printf("K = %d: mean %.2e worst %.2e\n", k, fit.meanError, fit.worstError);
        if (k == 2) {
            EXPECT_GT(fit.worstError, 1e-2);
        }
        EXPECT_LE(fit.worstError, previous * 1.0001);
        previous = fit.worstError;
    }
    EXPECT_LT(previous, 2e-2);
}

TEST(ColourBasisFit, TooFewPathsOrBadSettingsAreRefused) {
    const auto few = syntheticPaths(1, [](Rng&, size_t) { return 2; });
    testing::expectInputError(
        [&] {
            fitColourBasis(few, kBins, counts(), {0.3, 0.999}, 3);
        },
        {"too few", "gather more paths"});
    const auto paths =
        syntheticPaths(6, [](Rng&, size_t cell) { return static_cast<int>(cell % 5); });
    testing::expectInputError(
        [&] {
            fitColourBasis(paths, kBins, counts(), {0.3, 0.999}, 1);
        },
        {"colour basis functions = 1"});
    testing::expectInputError(
        [&] {
            fitColourBasis(paths, kBins, counts(), {0.0, 0.999}, 3);
        },
        {"colour range"});
}

}  // namespace
}  // namespace weft
