#include "weft/gather/gather.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "weft/core/math.h"
#include "weft/core/rng.h"
#include "weft/core/test_util.h"
#include "weft/fiber/fiber_bcsdf.h"
#include "weft/fiber/fiber_test_util.h"
#include "weft/gather/ply_tracer.h"

namespace weft {
namespace {

FiberParams losslessFiber() {
    // C_TT = 1: the albedo F + (1 - F) C_TT is exactly 1 in every channel.
    return {Rgb(0.04), Rgb(1.0), 7.0, 12.0, 25.0};
}

GatherOptions smallGather(const FiberParams& fiber, PlyParams ply, int64_t paths) {
    GatherOptions o;
    o.fiber = fiber;
    o.ply = ply;
    o.paths = paths;
    o.seed = 11;
    o.bins = {3, 8, 6, 12};
    o.quiet = true;
    return o;
}

// Energy leaving the ply for incident bin i (T + R + M integrated over the
// outgoing bins) plus the truncated energy, channel c.
double energyBalance(const GatherResult& r, size_t i, int c) {
    const size_t nOut = r.bins.outgoingCount();
    double e = r.pT[i] + r.truncated[i * 3 + c];
    for (size_t j = 0; j < nOut; ++j) {
        const size_t cell = (i * nOut + j) * 3 + c;
        e += (static_cast<double>(r.rdmR[cell]) + r.rdmM[cell]) * r.bins.outgoingSolidAngle(j);
    }
    return e;
}

TEST(RdmBins, SolidAnglesAndBinsAreConsistent) {
    const RdmBins bins;  // the paper's 22 x 90 x 45 x 90
    double sphere = 0, hemisphere = 0;
    for (size_t j = 0; j < bins.outgoingCount(); ++j) {
        sphere += bins.outgoingSolidAngle(j);
        EXPECT_EQ(bins.outgoingBin(bins.outgoingCentre(j)), j);
    }
    for (size_t i = 0; i < bins.incidentCount(); ++i) {
        hemisphere += bins.incidentSolidAngle(i);
        EXPECT_EQ(bins.incidentBin(bins.incidentCentre(i)), i);
    }
    EXPECT_NEAR(sphere, 4 * kPi, 1e-12);
    EXPECT_NEAR(hemisphere, 2 * kPi, 1e-12);
    // Conventions of docs/design.md 2: theta from n, phi from t towards b.
    EXPECT_EQ(bins.outgoingBin({0, 0, 1}) / bins.phiO, 0u);
    EXPECT_EQ(bins.outgoingBin({0, 0, -1}) / bins.phiO, 44u);
    EXPECT_EQ(bins.outgoingBin({1, 1e-9, 0}) % bins.phiO, 45u);  // phi = 0+ is the middle bin
    EXPECT_EQ(bins.outgoingBin({0, 1, 0}) % bins.phiO, 67u);     // phi = pi/2
    testing::expectInputError([] { RdmBins::parse("22,90,45"); }, {"TI,PI,TO,PO"});
    testing::expectInputError([] { RdmBins::parse("22,0,45,90"); }, {"phi_i = 0", "[1, 4096]"});
}

TEST(PlyTracer, FindsFibersSkipsTheExcludedOneAndWrapsPeriodically) {
    const PlyGeometry ply = generatePly({40, 0.1, 0.25}, 1.0, 1.0, 5);
    const PeriodicPlyTracer tracer(ply);
    EXPECT_NEAR(tracer.period(), 2.0 / 0.25, 1e-12);
    // Pick a fiber whose neighbours are all more than 3r away and which has
    // room to the bounding cylinder; a ray aimed at its centre line from 1.2r
    // away (in the plane z = z0) hits it first, unless it is excluded.
    const double r = ply.fiberRadius, z0 = 0.3 * tracer.period();
    int target = -1;
    for (int i = 0; i < 40 && target < 0; ++i) {
        const Vec3 ci = ply.fiberCentre(i, z0);
        bool isolated = std::hypot(ci.x, ci.y) + 1.3 * r < 1.0;
        for (int j = 0; j < 40; ++j)
            if (j != i && length(ply.fiberCentre(j, z0) - ci) < 3 * r) isolated = false;
        if (isolated) target = i;
    }
    ASSERT_GE(target, 0);
    const Vec3 c = ply.fiberCentre(target, z0);
    const Vec3 radial = normalize(Vec3(c.x, c.y, 0));
    const Vec3 from = c + radial * (1.2 * r);
    const PlyTraceHit hit = tracer.trace(from, -radial, -1);
    ASSERT_EQ(hit.kind, PlyTraceHit::Kind::Fiber);
    EXPECT_EQ(hit.fiber, target);
    // The tube surface (to the chord accuracy of 128 segments per twist).
    EXPECT_NEAR(length(hit.point - c), r, 0.02 * r);
    const PlyTraceHit skipped = tracer.trace(from, -radial, target);
    EXPECT_NE(skipped.fiber, target);
    // The cubic primitive (bench comparison) describes the same tube.
    const PeriodicPlyTracer cubic(ply, 32, FiberPrimitive::RoundCatmullRom);
    const PlyTraceHit cubicHit = cubic.trace(from, -radial, -1);
    ASSERT_EQ(cubicHit.kind, PlyTraceHit::Kind::Fiber);
    EXPECT_EQ(cubicHit.fiber, target);
    EXPECT_NEAR(length(cubicHit.point - c), r, 0.02 * r);
    // A ray along +z exactly on the axis of the empty ply (no fibers hit) wraps
    // until it gives up; one along z at the surface leaves at once.
    const PlyGeometry sparse = generatePly({1, 0.01, 0.0}, 1.0, 1.0, 1);
    const PeriodicPlyTracer empty(sparse);
    const Vec3 q = sparse.fiberCentre(0, 0);
    const Vec3 awayFromFiber =
        std::hypot(q.x, q.y) > 0.5 ? Vec3(0, 0, 0) : normalize(Vec3(q.x, q.y, 0)) * -0.8;
    const PlyTraceHit axial = empty.trace(awayFromFiber + Vec3(0, 0, 1.0), {0, 0, 1}, -1, 50);
    EXPECT_EQ(axial.kind, PlyTraceHit::Kind::ExitAxial);
    EXPECT_EQ(axial.raysTraced, 51);
    // A steep ray crossing several periods keeps the same xy path: it exits
    // the side after travelling the 2D chord.
    const Vec3 steep = normalize(Vec3(0.01, 0.0, 1.0));
    const Vec3 start = awayFromFiber + Vec3(0, 0, 0.5);
    const PlyTraceHit out = empty.trace(start, steep, 0, 10000);
    EXPECT_EQ(out.kind, PlyTraceHit::Kind::ExitSide);
    EXPECT_GT(out.raysTraced, 10);
    // Its exit point, unwrapped, is where the straight line meets the cylinder:
    // |start_xy + t steep_xy| = 1.
    const double qa = steep.x * steep.x + steep.y * steep.y;
    const double qb = start.x * steep.x + start.y * steep.y;
    const double qc = start.x * start.x + start.y * start.y - 1.0;
    const double t = (-qb + std::sqrt(qb * qb - qa * qc)) / qa;
    const Vec3 expected = start + steep * t;
    EXPECT_NEAR(out.point.x, expected.x, 1e-9);
    EXPECT_NEAR(out.point.y, expected.y, 1e-9);
    EXPECT_NEAR(out.point.z + out.periodShift * empty.period(), expected.z, 1e-6);
    EXPECT_GT(out.periodShift, 5);
    // Downwards, the same line backwards: the shift counts down.
    const PlyTraceHit back = empty.trace(start, -steep, 0, 10000);
    const double tBack = (qb + std::sqrt(qb * qb - qa * qc)) / qa;
    EXPECT_NEAR(back.point.z + back.periodShift * empty.period(), start.z - steep.z * tBack, 1e-6);
    EXPECT_LT(back.periodShift, -5);
}

TEST(Gather, ExitDistanceSummaryOfAKnownHistogram) {
    // Weight 1 in bin 3, 3 in bin 5, 1 beyond: mean over the range (bin
    // centres), quantiles linear within a bin.
    std::vector<double> h((kExitDistanceBins + 1) * 3, 0.0);
    h[3 * 3 + 1] = 1, h[5 * 3 + 1] = 3, h[kExitDistanceBins * 3 + 1] = 1;
    const ExitDistanceSummary e = summarizeExitDistance(h, 1);
    const double w = kExitDistanceBinWidth;
    EXPECT_DOUBLE_EQ(e.weight, 5);
    EXPECT_DOUBLE_EQ(e.mean, (1 * 3.5 + 3 * 5.5) / 4 * w);
    EXPECT_DOUBLE_EQ(e.beyondFraction, 0.2);
    EXPECT_DOUBLE_EQ(e.median, (5 + 1.5 / 3) * w);   // 2.5 of 5: 1.5 into bin 5's 3
    EXPECT_DOUBLE_EQ(e.p90, kExitDistanceBins * w);  // 4.5 of 5: the last bin
    EXPECT_EQ(summarizeExitDistance(h, 0).weight, 0);
    EXPECT_EQ(exitDistanceBin(0.0), 0);
    EXPECT_EQ(exitDistanceBin(0.99 * w), 0);
    EXPECT_EQ(exitDistanceBin(1e9), kExitDistanceBins);
}

TEST(Gather, ExitDistancesHoldTheMWeightAndCrossTwistPeriods) {
    // Lossless fibers, a sparse ply: the histogram of M exit distances holds
    // exactly the M energy of the RDM (two accumulations of the same paths),
    // and paths go farther than one twist period (z unwrapped).
    GatherOptions o = smallGather(losslessFiber(), {40, 0.2, 0.5}, testing::scaled(20000));
    const GatherResult r = gatherRdm(o);
    ASSERT_EQ(r.exitDistance.size(), static_cast<size_t>(kExitDistanceBins + 1) * 3);
    const size_t nOut = r.bins.outgoingCount();
    for (int c = 0; c < 3; ++c) {
        double fromRdm = 0, fromHistogram = 0, beyondPeriod = 0;
        for (size_t i = 0; i < r.bins.incidentCount(); ++i)
            for (size_t j = 0; j < nOut; ++j)
                fromRdm += static_cast<double>(r.rdmM[(i * nOut + j) * 3 + c]) *
                           r.bins.outgoingSolidAngle(j) * r.count[i] / o.paths;
        for (int b = 0; b <= kExitDistanceBins; ++b) {
            fromHistogram += r.exitDistance[b * 3 + c];
            if (b * kExitDistanceBinWidth > r.stats.period)
                beyondPeriod += r.exitDistance[b * 3 + c];
        }
        EXPECT_NEAR(fromHistogram, fromRdm, 1e-5 * fromRdm) << "channel " << c;
        EXPECT_GT(fromRdm, 0.1);
        EXPECT_GT(beyondPeriod, 0.0) << "period " << r.stats.period;
    }
    // Absorbing fibers (C_TT = 0.3) end paths sooner: their M light leaves nearer.
    o.fiber.cTT = Rgb(0.3);
    const GatherResult dark = gatherRdm(o);
    EXPECT_LT(summarizeExitDistance(dark.exitDistance, 0).mean,
              0.8 * summarizeExitDistance(r.exitDistance, 0).mean);
}

TEST(Gather, ExitOffsetSummaryOfAKnownHistogram) {
    const int mid = kExitOffsetAxialBins / 2;
    // Band 1, channel 2: weight 1 at (dz, dpsi) = (z0, p0) in one phi cell, 3
    // at (z1, p1) in another, 1 beyond: moments over bin centres.
    std::vector<double> h(kExitOffsetCells * kExitOffsetSlots * 3, 0.0);
    const auto at = [&](size_t cell, size_t slot) -> double& {
        return h[(cell * kExitOffsetSlots + slot) * 3 + 2];
    };
    const double w = kExitOffsetAxialWidth, dp = kTwoPi / kExitOffsetAroundBins;
    const double z0 = (3 + 0.5) * w, p0 = -kPi + 10.5 * dp, z1 = -(1 + 0.5) * w,
                 p1 = -kPi + 40.5 * dp;
    at(kExitOffsetPhi + 2, static_cast<size_t>(mid + 3) * kExitOffsetAroundBins + 10) = 1;
    at(kExitOffsetPhi + 6, static_cast<size_t>(mid - 2) * kExitOffsetAroundBins + 40) = 3;
    at(kExitOffsetPhi + 7, kExitOffsetSlots - 1) = 1;
    const ExitOffsetSummary e = summarizeExitOffset(h, 1, 2);
    EXPECT_DOUBLE_EQ(e.weight, 5);
    EXPECT_DOUBLE_EQ(e.beyondFraction, 0.2);
    EXPECT_NEAR(e.meanAxial, (z0 + 3 * z1) / 4, 1e-12);
    EXPECT_NEAR(e.meanAround, (p0 + 3 * p1) / 4, 1e-12);
    // Two points: sd = |difference| sqrt(q (1 - q)), correlation -1 (z falls as psi rises).
    EXPECT_NEAR(e.sdAxial, std::abs(z0 - z1) * std::sqrt(0.25 * 0.75), 1e-12);
    EXPECT_NEAR(e.sdAround, std::abs(p0 - p1) * std::sqrt(0.25 * 0.75), 1e-12);
    EXPECT_NEAR(e.correlation, -1.0, 1e-9);
    EXPECT_EQ(summarizeExitOffset(h, 0, 2).weight, 0);
    EXPECT_EQ(summarizeExitOffset(h, 1, 1).weight, 0);
}

TEST(Gather, ExitOffsetsHoldEachIncidentCellsMWeightAndMirrorWithoutTwist) {
    // Incident bins that are the offset cells (4 x 8): each cell holds the M
    // energy of its RDM bin (two accumulations of the same paths, binned by
    // two routines), all cells the exit distances' total. Straight fibers
    // (alpha = 0) make the ply its own mirror image in z, so the mean axial
    // offset is 0 within its standard error.
    GatherOptions o = smallGather(losslessFiber(), {40, 0.25, 0.0}, testing::scaled(20000));
    o.bins = {kExitOffsetTheta, kExitOffsetPhi, 6, 12};
    const GatherResult r = gatherRdm(o);
    ASSERT_EQ(r.exitOffset.size(), kExitOffsetCells * kExitOffsetSlots * 3);
    const size_t nOut = r.bins.outgoingCount();
    for (int c = 0; c < 3; ++c) {
        double total = 0, distances = 0;
        for (size_t i = 0; i < kExitOffsetCells; ++i) {
            double fromRdm = 0, fromOffsets = 0;
            for (size_t j = 0; j < nOut; ++j)
                fromRdm += static_cast<double>(r.rdmM[(i * nOut + j) * 3 + c]) *
                           r.bins.outgoingSolidAngle(j) * r.count[i] / o.paths;
            for (size_t k = 0; k < kExitOffsetSlots; ++k)
                fromOffsets += r.exitOffset[(i * kExitOffsetSlots + k) * 3 + c];
            EXPECT_NEAR(fromOffsets, fromRdm, 1e-5 * fromRdm + 1e-12)
                << "cell " << i << " channel " << c;
            total += fromOffsets;
        }
        for (int b = 0; b <= kExitDistanceBins; ++b) distances += r.exitDistance[b * 3 + c];
        EXPECT_NEAR(total, distances, 1e-12 * distances);
        EXPECT_GT(total, 0.1);
    }
    double weight = 0, moment = 0, square = 0, paths = 0;
    for (int a = 0; a < kExitOffsetTheta; ++a) {
        const ExitOffsetSummary e = summarizeExitOffset(r.exitOffset, a, 0);
        const double inRange = e.weight * (1 - e.beyondFraction);
        weight += inRange;
        moment += inRange * e.meanAxial;
        square += inRange * (sqr(e.sdAxial) + sqr(e.meanAxial));
    }
    // Lossless fibers: every M path has weight 1, so weight * paths counts them.
    paths = weight * o.paths;
    const double mean = moment / weight, sd = std::sqrt(square / weight - sqr(mean));
    EXPECT_GT(sd, 0.2);
    EXPECT_LT(std::abs(mean), 4 * sd / std::sqrt(paths)) << "mean " << mean << ", sd " << sd;
}

// RDM_M binned by wo in the exit frame (docs/exit-point.md): the same paths'
// energy per incident bin as RDM_M in the entry frame, and none of it below
// the exit point's horizon (a path leaves through the cylinder's side,
// outwards), where the entry frame sees a good part of it (light that
// crossed the ply and left on its far side).
TEST(Gather, ExitFrameMHoldsTheSameEnergyAndLeavesOutwards) {
    GatherOptions o =
        smallGather(testing::table3Fiber("fleece"), {80, 0.3, 0.25}, testing::scaled(20000));
    o.bins = {3, 8, 6, 12};  // theta_o bins of 30 degrees: the horizon is an edge
    const GatherResult r = gatherRdm(o);
    const size_t nIn = r.bins.incidentCount(), nOut = r.bins.outgoingCount();
    ASSERT_EQ(r.rdmMExit.size(), r.rdmM.size());
    for (int c = 0; c < 3; ++c) {
        double total = 0, belowEntry = 0, belowExit = 0;
        for (size_t i = 0; i < nIn; ++i) {
            double entry = 0, exit = 0;
            for (size_t j = 0; j < nOut; ++j) {
                const size_t cell = (i * nOut + j) * 3 + c;
                const double omega = r.bins.outgoingSolidAngle(j);
                entry += r.rdmM[cell] * omega;
                exit += r.rdmMExit[cell] * omega;
                if (r.bins.outgoingCentre(j).z < 0) {
                    belowEntry += r.rdmM[cell] * omega * r.count[i];
                    belowExit += r.rdmMExit[cell] * omega * r.count[i];
                }
            }
            EXPECT_NEAR(exit, entry, 1e-5 * entry + 1e-12) << "incident bin " << i;
            total += entry * r.count[i];
        }
        ASSERT_GT(total, 0.0);
        EXPECT_GT(belowEntry / total, 0.05) << "channel " << c;
        // Only paths that ran out along the axis keep the entry frame.
        EXPECT_LE(belowExit / total, static_cast<double>(r.stats.axialPaths) / o.paths + 1e-9)
            << "channel " << c;
        std::printf("channel %d: M below the horizon, entry frame %.3f, exit frame %.2g\n", c,
                    belowEntry / total, belowExit / total);
    }
}

TEST(Gather, LosslessFiberConservesEnergyInEveryIncidentBin) {
    GatherOptions o = smallGather(losslessFiber(), {80, 0.3, 0.2}, testing::scaled(40000));
    o.maxDepth = 8;  // some truncation, to check its bookkeeping too
    const GatherResult r = gatherRdm(o);
    EXPECT_GT(r.stats.truncatedPaths, 0);
    double worst = 0;
    for (size_t i = 0; i < r.bins.incidentCount(); ++i) {
        ASSERT_GT(r.count[i], 0);
        for (int c = 0; c < 3; ++c) {
            const double e = energyBalance(r, i, c);
            EXPECT_NEAR(e, 1.0, 1e-5) << "incident bin " << i << " channel " << c;
            worst = std::max(worst, std::fabs(e - 1.0));
        }
    }
    std::printf("lossless energy balance: largest |T + R + M + truncated - 1| = %.3g\n", worst);
}

// Independent transmission probability for straight fibers: a ray misses
// every (infinite, straight) fiber exactly when its projection on the cross
// section misses every disc of radius r.
TEST(Gather, StraightPlyTransmissionMatchesTwoDimensionalGeometry) {
    const PlyParams plyParams{120, 0.3, 0.0};
    const GatherOptions o =
        smallGather(testing::table3Fiber("fleece"), plyParams, testing::scaled(200000));
    const GatherResult r = gatherRdm(o);
    const PlyGeometry ply = generatePly(plyParams, 1.0, 1.0, o.seed);
    const double rf = ply.fiberRadius;
    const RdmBins& bins = o.bins;
    const int64_t perBin = testing::scaled(20000);
    double worstZ = 0;
    Rng rng(99, 1);
    for (size_t i = 0; i < bins.incidentCount(); ++i) {
        const int ti = static_cast<int>(i / bins.phiI), pi = static_cast<int>(i % bins.phiI);
        const double c0 = std::cos(ti * kHalfPi / bins.thetaI);
        const double c1 = std::cos((ti + 1) * kHalfPi / bins.thetaI);
        int64_t missed = 0;
        for (int64_t k = 0; k < perBin; ++k) {
            const double psi = kTwoPi * rng.uniform();
            const double cosTheta = c1 + (c0 - c1) * rng.uniform();
            const double sinTheta = std::sqrt(1 - cosTheta * cosTheta);
            const double phi = -kPi + (pi + rng.uniform()) * kTwoPi / bins.phiI;
            // Direction of travel -wi in 2D: n = (cos psi, sin psi), b = (-sin psi, cos psi).
            const double wb = sinTheta * std::sin(phi), wn = cosTheta;
            const double dx = -(wn * std::cos(psi) - wb * std::sin(psi));
            const double dy = -(wn * std::sin(psi) + wb * std::cos(psi));
            const double ex = std::cos(psi), ey = std::sin(psi);
            const double len2 = dx * dx + dy * dy;
            // Chord to the far side of the unit circle.
            const double tExit = -2 * (ex * dx + ey * dy) / len2;
            bool hit = false;
            for (const auto& c : ply.centres) {
                const double s =
                    std::clamp(((c[0] - ex) * dx + (c[1] - ey) * dy) / len2, 0.0, tExit);
                if (std::hypot(ex + s * dx - c[0], ey + s * dy - c[1]) < rf) {
                    hit = true;
                    break;
                }
            }
            missed += !hit;
        }
        const double pTest = static_cast<double>(missed) / perBin;
        const double p = 0.5 * (pTest + r.pT[i]);
        const double se =
            std::sqrt(std::max(p * (1 - p), 1e-4) * (1.0 / perBin + 1.0 / r.count[i]));
        const double z = std::fabs(r.pT[i] - pTest) / se;
        worstZ = std::max(worstZ, z);
        EXPECT_LT(z, 4.5) << "incident bin " << i << ": gather " << r.pT[i] << " vs 2D " << pTest;
    }
    std::printf("alpha = 0 P(T): largest |gather - 2D| / standard error = %.2f over %zu bins\n",
                worstZ, bins.incidentCount());
}

TEST(Gather, SingleFiberFirstBounceEnergyIsTheFiberAlbedo) {
    // One straight fiber: a path interacts at most once, and the expected
    // weight of an interacting path is the fiber's albedo at that angle.
    const FiberParams fleece = testing::table3Fiber("fleece");
    const PlyParams plyParams{1, 0.2, 0.0};
    const GatherOptions o = smallGather(fleece, plyParams, testing::scaled(400000));
    const GatherResult r = gatherRdm(o);
    for (size_t d = 2; d < r.depth.size(); ++d) EXPECT_EQ(r.depth[d], 0) << "depth " << d;
    const PlyGeometry ply = generatePly(plyParams, 1.0, 1.0, o.seed);
    const double cx = ply.centres[0][0], cy = ply.centres[0][1], rf = ply.fiberRadius;
    const RdmBins& bins = o.bins;
    const size_t nOut = bins.outgoingCount();
    const int64_t perBin = testing::scaled(100000);
    Rng rng(7, 7);
    for (size_t i = 0; i < bins.incidentCount(); ++i) {
        const int ti = static_cast<int>(i / bins.phiI), pi = static_cast<int>(i % bins.phiI);
        const double c0 = std::cos(ti * kHalfPi / bins.thetaI);
        const double c1 = std::cos((ti + 1) * kHalfPi / bins.thetaI);
        double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
        for (int64_t k = 0; k < perBin; ++k) {
            const double psi = kTwoPi * rng.uniform();
            const double cosTheta = c1 + (c0 - c1) * rng.uniform();
            const double sinTheta = std::sqrt(1 - cosTheta * cosTheta);
            const double phi = -kPi + (pi + rng.uniform()) * kTwoPi / bins.phiI;
            const double wt = sinTheta * std::cos(phi), wb = sinTheta * std::sin(phi),
                         wn = cosTheta;
            const double dx = -(wn * std::cos(psi) - wb * std::sin(psi));
            const double dy = -(wn * std::sin(psi) + wb * std::cos(psi));
            const double ex = std::cos(psi), ey = std::sin(psi), len2 = dx * dx + dy * dy;
            const double tExit = -2 * (ex * dx + ey * dy) / len2;
            const double s = std::clamp(((cx - ex) * dx + (cy - ey) * dy) / len2, 0.0, tExit);
            if (std::hypot(ex + s * dx - cx, ey + s * dy - cy) >= rf) continue;
            // Fiber along +z: cos(theta_f) = |d_xy| (the ray travels along -wi).
            const double cosFiber = std::sqrt(1 - wt * wt);
            const double m = 1 - cosFiber, schlick = m * m * m * m * m;
            for (int c = 0; c < 3; ++c) {
                const double f = fleece.cR[c] + (1 - fleece.cR[c]) * schlick;
                const double albedo = f + (1 - f) * fleece.cTT[c];
                sum[c] += albedo;
                sum2[c] += albedo * albedo;
            }
        }
        for (int c = 0; c < 3; ++c) {
            double gathered = 0;
            for (size_t j = 0; j < nOut; ++j) {
                const size_t cell = (i * nOut + j) * 3 + c;
                gathered +=
                    (static_cast<double>(r.rdmR[cell]) + r.rdmM[cell]) * bins.outgoingSolidAngle(j);
                // R is the upper hemisphere only (docs/design.md 5).
                if (static_cast<int>(j) / bins.phiO >= bins.thetaO / 2) {
                    EXPECT_EQ(r.rdmR[cell], 0.f);
                }
            }
            const double mean = sum[c] / perBin;
            const double var = sum2[c] / perBin - mean * mean;
            // The gather's per-path weight varies more than the albedo (lobe
            // choice); bound its variance by that of a 0/1 variable times 4.
            const double seGather = std::sqrt(std::max(4.0 * gathered, 1e-6) / r.count[i]);
            const double se = std::sqrt(var / perBin + seGather * seGather);
            EXPECT_NEAR(gathered, mean, 4.5 * se) << "incident bin " << i << " channel " << c;
        }
    }
}

TEST(Gather, ResultDoesNotDependOnThreadCountButOnSeed) {
    GatherOptions o =
        smallGather(testing::table3Fiber("polyester"), {60, 0.4, 0.2}, testing::scaled(20000));
    o.threads = 1;
    const GatherResult one = gatherRdm(o);
    o.threads = 2;
    const GatherResult two = gatherRdm(o);
    EXPECT_EQ(one.count, two.count);
    EXPECT_EQ(one.countT, two.countT);
    EXPECT_EQ(one.depth, two.depth);
    ASSERT_EQ(one.rdmM.size(), two.rdmM.size());
    EXPECT_EQ(0, std::memcmp(one.rdmM.data(), two.rdmM.data(), one.rdmM.size() * sizeof(float)));
    EXPECT_EQ(0, std::memcmp(one.rdmR.data(), two.rdmR.data(), one.rdmR.size() * sizeof(float)));
    EXPECT_EQ(one.truncated, two.truncated);
    EXPECT_EQ(0, std::memcmp(one.rdmMExit.data(), two.rdmMExit.data(),
                             one.rdmMExit.size() * sizeof(float)));
    o.seed = 12;
    const GatherResult other = gatherRdm(o);
    EXPECT_NE(0, std::memcmp(one.rdmM.data(), other.rdmM.data(), one.rdmM.size() * sizeof(float)));
    EXPECT_NE(one.plyLines, other.plyLines);
    // --ply-seed fixes the placement while the walks change.
    o.plySeed = 11;
    const GatherResult samePly = gatherRdm(o);
    EXPECT_EQ(one.plyLines, samePly.plyLines);
    EXPECT_NE(0,
              std::memcmp(one.rdmM.data(), samePly.rdmM.data(), one.rdmM.size() * sizeof(float)));
}

TEST(Gather, InvalidOptionsAreRejected) {
    GatherOptions o = smallGather(losslessFiber(), {80, 0.3, 0.2}, 0);
    testing::expectInputError([&] { gatherRdm(o); }, {"paths = 0"});
    o.paths = 10;
    o.maxDepth = 0;
    testing::expectInputError([&] { gatherRdm(o); }, {"max depth = 0"});
    o.maxDepth = 10;
    o.ply = {300, 0.95, 0.1};
    testing::expectInputError([&] { gatherRdm(o); }, {"N=300", "rho=0.95"});
    o.ply = {80, 0.3, 0.2};
    o.segmentsPerTwist = 4;
    testing::expectInputError([&] { gatherRdm(o); }, {"segments per twist = 4"});
}

}  // namespace
}  // namespace weft
