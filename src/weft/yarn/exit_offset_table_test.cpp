// The model's exit-offset density (yarn/exit_offset_table.h): merged bins
// keep their mass, the density integrates to 1, samples follow it (Pearson
// chi-square), cells without M light have none, bad input is refused.
#include "weft/yarn/exit_offset_table.h"

#include <gtest/gtest.h>

#include <cmath>

#include "weft/core/chi2.h"
#include "weft/core/error.h"
#include "weft/core/math.h"
#include "weft/core/rng.h"
#include "weft/core/test_util.h"

namespace weft {
namespace {

using Histogram = std::vector<double>;

double& weightAt(Histogram& h, size_t cell, size_t slot, int c) {
    return h[(cell * kExitOffsetSlots + slot) * 3 + c];
}

// A gather-like histogram: cell 5, channel 1 a heavy-tailed blob around
// (0.3, -0.5), correlated; cell 5, channel 0 one fine slot; some mass beyond
// the axial range; every other cell and channel empty.
Histogram testHistogram() {
    Histogram h(kExitOffsetCells * kExitOffsetSlots * 3, 0.0);
    for (int i = 0; i < kExitOffsetAxialBins; ++i)
        for (int j = 0; j < kExitOffsetAroundBins; ++j) {
            const double z = (i + 0.5 - 0.5 * kExitOffsetAxialBins) * kExitOffsetAxialWidth;
            const double p = -kPi + (j + 0.5) * kTwoPi / kExitOffsetAroundBins;
            const double r = std::hypot(z - 0.3 - 0.4 * (p + 0.5), p + 0.5);
            weightAt(h, 5, static_cast<size_t>(i) * kExitOffsetAroundBins + j, 1) =
                1.0 / (1.0 + 4 * r * r * r);
        }
    weightAt(h, 5, kExitOffsetSlots - 1, 1) = 3.0;  // beyond: left out
    weightAt(h, 5, 70 * kExitOffsetAroundBins + 9, 0) = 0.25;
    return h;
}

TEST(ExitOffsetTable, MergedBinsKeepTheirMassAndTheDensityIntegratesToOne) {
    Histogram h = testHistogram();
    const ExitOffsetTable t = ExitOffsetTable::fromHistogram(h, 4, 2, "test");
    EXPECT_EQ(t.axialBins(), kExitOffsetAxialBins / 4);
    EXPECT_EQ(t.aroundBins(), kExitOffsetAroundBins / 2);
    EXPECT_DOUBLE_EQ(t.axialRange(), 0.5 * kExitOffsetAxialBins * kExitOffsetAxialWidth);
    EXPECT_TRUE(t.hasDensity(5, 1));
    EXPECT_TRUE(t.hasDensity(5, 0));
    EXPECT_FALSE(t.hasDensity(5, 2));
    EXPECT_FALSE(t.hasDensity(4, 1));
    // The merged bin (rows 68-71, columns 8-9) of channel 0 holds all of it.
    const double dz = (70 + 0.5 - 0.5 * kExitOffsetAxialBins) * kExitOffsetAxialWidth,
                 dpsi = -kPi + 9.5 * kTwoPi / kExitOffsetAroundBins;
    EXPECT_NEAR(t.pdf(5, 0, dz, dpsi) * t.axialWidth() * t.aroundWidth(), 1.0, 1e-6);
    EXPECT_EQ(t.pdf(5, 0, dz + t.axialWidth(), dpsi), 0.0);
    // Midpoint sums of the density over each bin: 1; and each merged bin's
    // probability is its fine bins' share of the weight within the range.
    double integral = 0, inRange = 0;
    for (int i = 0; i < kExitOffsetAxialBins; ++i)
        for (int j = 0; j < kExitOffsetAroundBins; ++j)
            inRange += weightAt(h, 5, static_cast<size_t>(i) * kExitOffsetAroundBins + j, 1);
    for (int i = 0; i < t.axialBins(); ++i)
        for (int j = 0; j < t.aroundBins(); ++j) {
            const double z = -t.axialRange() + (i + 0.5) * t.axialWidth(),
                         p = -kPi + (j + 0.5) * t.aroundWidth();
            const double probability = t.pdf(5, 1, z, p) * t.axialWidth() * t.aroundWidth();
            integral += probability;
            double fine = 0;
            for (int a = 4 * i; a < 4 * i + 4; ++a)
                for (int b = 2 * j; b < 2 * j + 2; ++b)
                    fine += weightAt(h, 5, static_cast<size_t>(a) * kExitOffsetAroundBins + b, 1);
            ASSERT_NEAR(probability, fine / inRange, 1e-6) << i << " " << j;
        }
    EXPECT_NEAR(integral, 1.0, 1e-5);
    // Outside the range, or a cell without density: 0; its sample: no offset.
    EXPECT_EQ(t.pdf(5, 1, t.axialRange() + 0.01, 0.0), 0.0);
    EXPECT_EQ(t.pdf(4, 1, 0.1, 0.1), 0.0);
    const ExitOffsetTable::Offset none = t.sample(4, 1, 0.3, 0.7);
    EXPECT_EQ(none.dz, 0.0);
    EXPECT_EQ(none.dpsi, 0.0);
    EXPECT_EQ(none.pdf, 0.0);
}

TEST(ExitOffsetTable, SamplesFollowThePdf) {
    const ExitOffsetTable t = ExitOffsetTable::fromHistogram(testHistogram(), 2, 2, "test");
    const int nz = t.axialBins(), np = t.aroundBins();
    const int samples = testing::scaled(400000);
    std::vector<double> observed(static_cast<size_t>(nz) * np, 0.0), expected(observed.size());
    Rng rng(3, 5);
    for (int k = 0; k < samples; ++k) {
        const ExitOffsetTable::Offset o = t.sample(5, 1, rng.uniform(), rng.uniform());
        ASSERT_GT(o.pdf, 0.0);
        ASSERT_EQ(o.pdf, t.pdf(5, 1, o.dz, o.dpsi)) << o.dz << " " << o.dpsi;
        const int i = static_cast<int>((o.dz + t.axialRange()) / t.axialWidth());
        const int j = static_cast<int>((o.dpsi + kPi) / t.aroundWidth());
        ASSERT_TRUE(i >= 0 && i < nz && j >= 0 && j < np) << o.dz << " " << o.dpsi;
        observed[static_cast<size_t>(i) * np + j] += 1;
    }
    for (int i = 0; i < nz; ++i)
        for (int j = 0; j < np; ++j)
            expected[static_cast<size_t>(i) * np + j] =
                samples *
                t.pdf(5, 1, -t.axialRange() + (i + 0.5) * t.axialWidth(),
                      -kPi + (j + 0.5) * t.aroundWidth()) *
                t.axialWidth() * t.aroundWidth();
    const Chi2Result r = chi2Test(observed, expected);
    EXPECT_GT(r.pValue, 0.01) << "chi2 " << r.statistic << " dof " << r.dof;
    // Within a bin the offset is uniform: the mean of dz over samples in
    // one wide bin is its centre.
    const ExitOffsetTable coarse = ExitOffsetTable::fromHistogram(testHistogram(), 128, 64, "test");
    double sum = 0;
    for (int k = 0; k < 10000; ++k) sum += coarse.sample(5, 1, rng.uniform(), rng.uniform()).dz;
    EXPECT_NEAR(sum / 10000, 0.0, 4 * coarse.axialRange() / std::sqrt(3.0 * 10000));
}

TEST(ExitOffsetTable, RefusesBadHistogramsAndMerges) {
    Histogram h = testHistogram();
    testing::expectInputError(
        [&] { ExitOffsetTable::fromHistogram(h, 3, 1, "gather exit_offset"); },
        {"gather exit_offset", "merged 3 x 1", "divide 128 x 64"});
    testing::expectInputError([&] { ExitOffsetTable::fromHistogram(h, 1, 0, "x"); }, {"0"});
    weightAt(h, 2, 17, 1) = -1;
    testing::expectInputError([&] { ExitOffsetTable::fromHistogram(h, 1, 1, "x"); },
                              {"cell 2, slot 17, channel 1", "-1", ">= 0"});
    weightAt(h, 2, 17, 1) = std::nan("");
    testing::expectInputError([&] { ExitOffsetTable::fromHistogram(h, 1, 1, "x"); },
                              {"cell 2, slot 17", "finite"});
    testing::expectInputError(
        [&] {
            ExitOffsetTable::fromHistogram({1.0, 2.0}, 1, 1, "x");
        },
        {"2 numbers", "expected"});
}

}  // namespace
}  // namespace weft
