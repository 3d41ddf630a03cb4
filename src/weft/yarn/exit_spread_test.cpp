// The yarn BSDF's exit spread (yarn_bsdf.h, "Exit offsets"; issue 47): the
// split event is another estimator of the same BSDF. Its parts sum to eval
// and pdf, its continuation weights average to the albedo that sample()'s
// weights average to, each channel's offset weight averages to that
// channel's offset density (the channel MIS), and each branch's directions
// follow its density (chi-square).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "weft/core/chi2.h"
#include "weft/core/math.h"
#include "weft/core/rng.h"
#include "weft/core/sampling.h"
#include "weft/core/test_util.h"
#include "weft/yarn/yarn_bsdf.h"
#include "weft/yarn/yarn_test_util.h"

namespace weft {
namespace {

using weft::testing::scaled;

// Per cell and channel a different blob of offsets: centred on dz = 0.5 (c -
// 1), dpsi = 0.3 c - 0.3, wider in blue; every cell has all three channels.
ExitOffsetTable spreadTable() {
    std::vector<double> h(kExitOffsetCells * kExitOffsetSlots * 3, 0.0);
    for (size_t cell = 0; cell < kExitOffsetCells; ++cell)
        for (int c = 0; c < 3; ++c)
            for (int i = 0; i < kExitOffsetAxialBins; ++i)
                for (int j = 0; j < kExitOffsetAroundBins; ++j) {
                    const double z = (i + 0.5 - 0.5 * kExitOffsetAxialBins) * kExitOffsetAxialWidth;
                    const double p = -kPi + (j + 0.5) * kTwoPi / kExitOffsetAroundBins;
                    const double width = 0.4 + 0.5 * c;
                    const double r2 = sqr((z - 0.5 * (c - 1)) / width) + sqr(p - 0.3 * c + 0.3);
                    h[(cell * kExitOffsetSlots + static_cast<size_t>(i) * kExitOffsetAroundBins +
                       j) *
                          3 +
                      c] = std::exp(-r2) * (1 + 0.1 * static_cast<double>(cell % 5));
                }
    return ExitOffsetTable::fromHistogram(h, ExitOffsetTable::defaultEdges(), "test");
}

YarnModel spreadModel() {
    YarnModel model = loadYarnModel(testing::testModelPath("fleece-small"));
    model.exitOffset = spreadTable();
    return model;
}

// Incident directions from above, and a channel importance (the path
// throughput) far from grey, so that the channel pick matters.
const Vec3 kIncident[] = {normalize(Vec3{0.3, 0.2, 0.9}), normalize(Vec3{-0.6, 0.5, 0.4}),
                          normalize(Vec3{0.9, -0.1, 0.2})};
const Rgb kImportance{1.0, 0.3, 0.08};

BsdfIncident prepared(const YarnBsdf& bsdf, const Vec3& wi) {
    BsdfIncident in;
    in.setImportance(kImportance);
    bsdf.prepare(wi, in);
    return in;
}

TEST(ExitSpread, OnlyModelsWithTheTableSplitAndOnlyFromAbove) {
    const YarnBsdf plain(loadYarnModel(testing::testModelPath("fleece-small")));
    EXPECT_EQ(plain.exitSpread(), nullptr);
    const YarnBsdf bsdf(spreadModel());
    ASSERT_NE(bsdf.exitSpread(), nullptr);
    EXPECT_TRUE(bsdf.splits(prepared(bsdf, kIncident[0])));
    // From inside the tube (mirrored): today's event.
    EXPECT_FALSE(bsdf.splits(prepared(bsdf, mirrored(kIncident[0]))));
}

TEST(ExitSpread, PartsSumToTheBsdfAndItsDensity) {
    const YarnBsdf bsdf(spreadModel());
    Rng rng(5, 7);
    for (const Vec3& wi : kIncident) {
        const BsdfIncident in = prepared(bsdf, wi);
        for (int k = 0; k < 200; ++k) {
            const Vec3 wo = sampleUniformSphere(rng.uniform(), rng.uniform());
            const BsdfEval whole = bsdf.evalPdf(in, wo);
            const BsdfEval surface = bsdf.evalSurface(in, wo), m = bsdf.evalSpread(in, wo);
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(surface.value[c] + m.value[c], whole.value[c],
                            1e-12 * (1 + whole.value[c]));
            ASSERT_NEAR(surface.pdf + m.pdf, whole.pdf, 1e-12 * (1 + whole.pdf));
        }
    }
}

TEST(ExitSpread, EventWeightsAverageToTheAlbedoOfSample) {
    // Two estimators of the albedo at wi: sample()'s weight, and the split
    // event's continuation (the surface part's weight, or the spread part's
    // times the offset weight).
    const YarnBsdf bsdf(spreadModel());
    const int n = static_cast<int>(scaled(200000));
    for (const Vec3& wi : kIncident) {
        const BsdfIncident in = prepared(bsdf, wi);
        Rng rng(11, static_cast<uint64_t>(1e6 * (wi.x + 2 * wi.y + 3 * wi.z)) + 1000000);
        Rgb sum[2], sum2[2];
        int spreads = 0;
        for (int k = 0; k < n; ++k) {
            const BsdfSampleInput u = {rng.uniform(), rng.uniform(), rng.uniform()};
            const BsdfSampleInput uOffset = {rng.uniform(), rng.uniform(), rng.uniform()};
            const BsdfSample s = bsdf.sample(in, u, rng);
            const Rgb plain = s.valid() ? s.weight : Rgb(0.0);
            const SpreadSample e = bsdf.sampleEvent(in, u, rng);
            Rgb split = e.sample.valid() ? e.sample.weight : Rgb(0.0);
            if (e.spread) {
                ++spreads;
                split *= bsdf.sampleOffset(in, uOffset).weight;
            }
            sum[0] += plain, sum2[0] += plain * plain;
            sum[1] += split, sum2[1] += split * split;
        }
        for (int c = 0; c < 3; ++c) {
            double mean[2], variance[2];
            for (int a = 0; a < 2; ++a) {
                mean[a] = sum[a][c] / n;
                variance[a] = std::max(0.0, sum2[a][c] / n - sqr(mean[a])) / n;
            }
            EXPECT_NEAR(mean[1], mean[0], 4 * std::sqrt(variance[0] + variance[1]) + 1e-4)
                << "wi " << wi << " channel " << c;
        }
        // Both branches happen.
        EXPECT_GT(spreads, n / 50);
        EXPECT_LT(spreads, n - n / 50);
    }
}

TEST(ExitSpread, ChannelWeightsAverageToEachChannelsOffsetDensity) {
    // E[weight_c 1(offset in B)] = q_c(B) for a row B of dz bins, whichever
    // channel each offset picked (one-sample MIS over channels).
    const YarnModel model = spreadModel();
    const YarnBsdf bsdf(model);
    const ExitOffsetTable& table = *model.exitOffset;
    const std::vector<double>& dz = table.edges().dz;
    const int n = static_cast<int>(scaled(300000));
    const Vec3 wi = kIncident[1];
    const BsdfIncident in = prepared(bsdf, wi);
    const size_t cell = exitOffsetCell(wi);
    std::vector<Rgb> sum(dz.size() - 1), sum2(dz.size() - 1);
    Rng rng(17, 19);
    for (int k = 0; k < n; ++k) {
        const SpreadOffset o = bsdf.sampleOffset(in, {rng.uniform(), rng.uniform(), rng.uniform()});
        const size_t row = std::upper_bound(dz.begin(), dz.end(), o.dz) - dz.begin() - 1;
        sum[row] += o.weight, sum2[row] += o.weight * o.weight;
    }
    for (int c = 0; c < 3; ++c) {
        double total = 0;
        for (size_t row = 0; row + 1 < dz.size(); ++row) {
            double expected = 0;
            for (int j = 0; j < table.aroundBins(); ++j)
                expected += table.probability(cell, c, static_cast<int>(row), j);
            const double mean = sum[row][c] / n;
            const double se = std::sqrt(std::max(0.0, sum2[row][c] / n - mean * mean) / n);
            // (+ 5e-4: a row that rare offsets never reached has no spread of its own)
            EXPECT_NEAR(mean, expected, 4 * se + 5e-4) << "channel " << c << " row " << row;
            total += mean;
        }
        EXPECT_NEAR(total, 1.0, 0.01) << "channel " << c;
    }
}

TEST(ExitSpread, BranchDirectionsFollowTheirDensities) {
    // Each branch's continuations against its density (evalSurface's,
    // evalSpread's), Pearson chi-square; the T lobe is one more cell of the
    // surface branch.
    const YarnBsdf bsdf(spreadModel());
    const SphereGrid grid{10, 20};
    const int64_t n = scaled(200000);
    for (const Vec3& wi : kIncident) {
        const BsdfIncident in = prepared(bsdf, wi);
        std::vector<double> observed[2];
        for (auto& o : observed) o.assign(grid.cells() + 1, 0.0);
        Rng rng(23, static_cast<uint64_t>(1e6 * (wi.x + 2 * wi.y + 3 * wi.z)) + 1000000);
        for (int64_t k = 0; k < n; ++k) {
            const SpreadSample e =
                bsdf.sampleEvent(in, {rng.uniform(), rng.uniform(), rng.uniform()}, rng);
            ASSERT_TRUE(e.sample.valid());
            if (!e.sample.isDelta) {
                const BsdfEval at =
                    e.spread ? bsdf.evalSpread(in, e.sample.wo) : bsdf.evalSurface(in, e.sample.wo);
                ASSERT_NEAR(e.sample.pdf, at.pdf, 1e-12 * e.sample.pdf);
            }
            observed[e.spread][e.sample.isDelta ? grid.cells() : grid.cellOf(e.sample.wo)] += 1;
        }
        for (const bool spread : {false, true}) {
            std::vector<double> expected = grid.expectedCounts(
                [&](const Vec3& wo) {
                    return (spread ? bsdf.evalSpread(in, wo) : bsdf.evalSurface(in, wo)).pdf;
                },
                static_cast<double>(n));
            expected.push_back(spread ? 0.0 : n * bsdf.lobeProbabilities(wi).t);
            const Chi2Result r = chi2Test(observed[spread], expected);
            EXPECT_GT(r.pValue, 1e-3) << "wi " << wi << (spread ? " spread" : " surface")
                                      << " chi2 " << r.statistic << " dof " << r.dof;
        }
    }
}

// The offset's channel probabilities: 3/4 by the M light each channel
// carries at wi (importance x E_M x the factor on S_M; E_M, the integral of
// S_M (cosine included) over the sphere, here by Monte Carlo, the BSDF's own
// by the energy guard's Gauss-Legendre rule), 1/4 by the importance alone;
// every channel with M light keeps a share.
TEST(ExitSpread, ChannelProbabilitiesFollowTheLightEachChannelCarries) {
    const YarnBsdf bsdf(spreadModel());
    const int n = static_cast<int>(scaled(200000));
    for (const Rgb& importance : {Rgb(1.0), kImportance}) {
        for (const Vec3& direction : kIncident) {
            // The cell's central direction (where the BSDF integrates E_M).
            const double theta = std::acos(direction.z), phi = std::atan2(direction.y, direction.x);
            const int i = std::min(3, static_cast<int>(theta / (kHalfPi / 4)));
            const int j = std::min(7, static_cast<int>((phi + kPi) / (kTwoPi / 8)));
            const double thetaC = (i + 0.5) * kHalfPi / 4, phiC = -kPi + (j + 0.5) * kTwoPi / 8;
            const Vec3 wi{std::sin(thetaC) * std::cos(phiC), std::sin(thetaC) * std::sin(phiC),
                          std::cos(thetaC)};
            Rgb albedo(0.0);
            Rng rng(7, 11);
            for (int k = 0; k < n; ++k) {
                const Vec3 wo = sampleUniformSphere(rng.uniform(), rng.uniform());
                albedo += bsdf.model().evalM(wi, wo);
            }
            albedo = albedo * (4 * kPi / n);
            BsdfIncident in;
            in.setImportance(importance);
            bsdf.prepare(wi, in);
            const YarnIncident& yarn = in.get<YarnIncident>();
            const Rgb carried = importance * albedo * yarn.mScale;
            const double total = carried.r + carried.g + carried.b;
            const double sum = importance.r + importance.g + importance.b;
            const Rgb& p = yarn.spreadChannel;
            EXPECT_NEAR(p.r + p.g + p.b, 1.0, 1e-12);
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(p[c], 0.75 * carried[c] / total + 0.25 * importance[c] / sum, 0.01)
                    << "wi " << wi << " channel " << c;
                EXPECT_GE(p[c], 0.25 * importance[c] / sum - 1e-12);
            }
        }
    }
}

// The spread batches (evalSpreadBatch, sampleEventBatch) give every query
// the single call's bits, and prepareBatch the same split decisions and
// offsets as prepare: incidents from both sides (mirrored ones do not
// split), any mix of T, surface and spread continuations, in batches that
// are single, partial and larger than a chunk.
TEST(ExitSpread, BatchesGiveTheSingleCallsBits) {
    const YarnBsdf bsdf(spreadModel());
    Rng rng(31, 3);
    for (const size_t count : {size_t(1), size_t(15), size_t(70), size_t(200)}) {
        testing::BatchQueries q(bsdf, count, rng, 9);
        std::vector<BsdfSampleInput> uOffset(count);
        for (auto& v : uOffset) v = {rng.uniform(), rng.uniform(), rng.uniform()};
        std::vector<BsdfEval> evals(count);
        bsdf.evalSpreadBatch(q.batchConst.data(), q.wo.data(), count, evals.data());
        std::vector<SpreadSample> samples(count);
        bsdf.sampleEventBatch(q.batchConst.data(), q.u.data(), q.rngPtr.data(), count,
                              samples.data());
        int spreads = 0;
        for (size_t k = 0; k < count; ++k) {
            SCOPED_TRACE("query " + std::to_string(k) + " of " + std::to_string(count));
            ASSERT_EQ(bsdf.splits(q.batch[k]), bsdf.splits(q.single[k]));
            ASSERT_EQ(bsdf.splits(q.single[k]), q.wi[k].z >= 0);
            if (!bsdf.splits(q.single[k])) continue;
            const SpreadOffset o = bsdf.sampleOffset(q.single[k], uOffset[k]);
            const SpreadOffset ob = bsdf.sampleOffset(q.batch[k], uOffset[k]);
            ASSERT_EQ(ob.dz, o.dz);
            ASSERT_EQ(ob.dpsi, o.dpsi);
            ASSERT_EQ(ob.weight, o.weight);
            const BsdfEval want = bsdf.evalSpread(q.single[k], q.wo[k]);
            ASSERT_EQ(evals[k].value, want.value);
            ASSERT_EQ(evals[k].pdf, want.pdf);
            const SpreadSample s = bsdf.sampleEvent(q.single[k], q.u[k], q.rngSingle[k]);
            spreads += s.spread;
            ASSERT_EQ(samples[k].spread, s.spread);
            ASSERT_EQ(samples[k].sample.lobe, s.sample.lobe);
            ASSERT_EQ(samples[k].sample.wo, s.sample.wo);
            ASSERT_EQ(samples[k].sample.weight, s.sample.weight);
            ASSERT_EQ(samples[k].sample.pdf, s.sample.pdf);
            ASSERT_EQ(samples[k].sample.isDelta, s.sample.isDelta);
            ASSERT_EQ(q.rngBatch[k].nextU32(), q.rngSingle[k].nextU32());
        }
        if (count >= 70) {
            EXPECT_GT(spreads, 0);
        }
    }
}

}  // namespace
}  // namespace weft
