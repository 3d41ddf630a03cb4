#include "weft/render/curve_report.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "weft/core/math.h"
#include "weft/core/rng.h"
#include "weft/core/test_util.h"

namespace weft::render {
namespace {

using testing::expectInputError;

constexpr double kInf = std::numeric_limits<double>::infinity();

Curve polyline(std::vector<Vec3> points, bool closed = false) {
    Curve c;
    c.points = std::move(points);
    c.closed = closed;
    return c;
}

// n + 1 points from a to b.
Curve straightLine(const Vec3& a, const Vec3& b, int n) {
    std::vector<Vec3> points;
    for (int k = 0; k <= n; ++k) points.push_back(a + (b - a) * (static_cast<double>(k) / n));
    return polyline(points);
}

// ---------------------------------------------------------------------------
// The brute-force truth: every pair of segments, in curve order, with the
// contact rule of curve_report.h written out again.

struct FlatSegment {
    Vec3 a, b;
    size_t curve;
    double arcStart, length, curveLength;
    bool closed;
};

std::vector<FlatSegment> flatten(const CurveSet& set) {
    std::vector<FlatSegment> out;
    for (size_t c = 0; c < set.curves.size(); ++c) {
        const Curve& curve = set.curves[c];
        const size_t n = curve.points.size();
        const size_t spans = curve.closed ? n : n - 1;
        const size_t first = out.size();
        double arc = 0;
        for (size_t k = 0; k < spans; ++k) {
            const Vec3 a = curve.points[k], b = curve.points[(k + 1) % n];
            out.push_back({a, b, c, arc, length(b - a), 0, curve.closed});
            arc += length(b - a);
        }
        for (size_t k = first; k < out.size(); ++k) out[k].curveLength = arc;
    }
    return out;
}

struct BruteContact {
    double distance = kInf;
    size_t curveA = 0, curveB = 0;
    Vec3 pointA, pointB;
};

// The closest contact pair; with `counts`, among the pairs of curves it accepts.
BruteContact bruteForceContact(const CurveSet& set,
                               const std::function<bool(size_t, size_t)>& counts = {}) {
    const std::vector<FlatSegment> segs = flatten(set);
    BruteContact best;
    for (size_t i = 0; i < segs.size(); ++i) {
        for (size_t j = i + 1; j < segs.size(); ++j) {
            const FlatSegment &s = segs[i], &t = segs[j];
            if (counts && !counts(s.curve, t.curve)) continue;
            const SegmentClosestPoints cp = closestPointsOnSegments(s.a, s.b, t.a, t.b);
            if (s.curve == t.curve) {
                double sep = std::fabs(s.arcStart + cp.s * s.length - t.arcStart - cp.t * t.length);
                if (s.closed) sep = std::min(sep, s.curveLength - sep);
                if (!(sep > 2 * cp.distance)) continue;
            }
            if (cp.distance < best.distance) best = {cp.distance, s.curve, t.curve, cp.p, cp.q};
        }
    }
    return best;
}

// The overlap of curve_report.h at `radius` written out again: every sample
// of every segment against every segment.
struct BruteOverlap {
    double fraction = 0, maxDepth = 0;
    size_t curvesOverlapping = 0;
};

BruteOverlap bruteForceOverlap(const CurveSet& set, double radius) {
    const std::vector<FlatSegment> segs = flatten(set);
    const double bound = radius * (1 - 2 * kOverlapTolerance);
    double total = 0, overlapping = 0;
    BruteOverlap result;
    std::vector<char> overlaps(set.curves.size(), 0);
    for (const FlatSegment& s : segs) {
        total += s.length;
        const int n = static_cast<int>(
            std::clamp(std::ceil(s.length / (0.25 * radius)), 1.0, double{kMaxSamplesPerSegment}));
        for (int k = 0; k <= n; ++k) {
            const double u = static_cast<double>(k) / n;
            const Vec3 x = s.a + (s.b - s.a) * u;
            const double arc = s.arcStart + u * s.length;
            double g = kInf;
            for (const FlatSegment& t : segs) {
                const Vec3 d = t.b - t.a;
                const double len2 = dot(d, d);
                const double v = len2 > 0 ? std::clamp(dot(x - t.a, d) / len2, 0.0, 1.0) : 0.0;
                if (t.curve == s.curve) {
                    double sep = std::fabs(arc - (t.arcStart + v * t.length));
                    if (t.closed) sep = std::min(sep, t.curveLength - sep);
                    if (!(sep > 4 * radius)) continue;
                }
                g = std::min(g, length(x - (t.a + d * v)) - radius);
            }
            if (!(g < bound)) continue;
            overlapping += s.length / n * (k == 0 || k == n ? 0.5 : 1.0);
            result.maxDepth = std::max(result.maxDepth, 0.5 - 0.5 * g / radius);
            overlaps[s.curve] = 1;
        }
    }
    result.fraction = total > 0 ? std::min(1.0, overlapping / total) : 0.0;
    for (const char o : overlaps) result.curvesOverlapping += o ? 1 : 0;
    return result;
}

// Two-point curves from random points of a box of side `box` (issue 41's
// hostile input: long segments criss-crossing each other), after the curves
// of `set`; every `twins`-th one again, the same segment twice (ties).
CurveSet withRandomSegments(CurveSet set, uint64_t seed, int count, double box, int twins = 0) {
    Rng rng(seed, 9);
    const auto point = [&] { return Vec3{rng.uniform(), rng.uniform(), rng.uniform()} * box; };
    for (int i = 0; i < count; ++i) {
        set.curves.push_back(polyline({point(), point()}));
        if (twins > 0 && i % twins == 0) set.curves.push_back(set.curves.back());
    }
    return set;
}

// Random-walk curves in a small box: close approaches between curves and
// within one, some closed.
CurveSet randomWalks(uint64_t seed, int curves, int points, double box = 4, double step = 0.8,
                     bool planar = false) {
    Rng rng(seed, 7);
    CurveSet set;
    for (int c = 0; c < curves; ++c) {
        Vec3 p{box * rng.uniform(), box * rng.uniform(), box * rng.uniform()};
        std::vector<Vec3> pts;
        for (int k = 0; k < points; ++k) {
            pts.push_back(p);
            p += Vec3{rng.uniform() - 0.5, rng.uniform() - 0.5, planar ? 0 : rng.uniform() - 0.5} *
                 step;
        }
        set.curves.push_back(polyline(pts, c % 3 == 2));
    }
    return set;
}

// ---------------------------------------------------------------------------

TEST(ClosestPointsOnSegments, NoGridPointPairIsCloser) {
    Rng rng(3, 1);
    const auto point = [&] { return Vec3{rng.uniform(), rng.uniform(), rng.uniform()} * 2.0; };
    for (int trial = 0; trial < 300; ++trial) {
        Vec3 p1 = point(), q1 = point(), p2 = point(), q2 = point();
        if (trial % 10 == 1) q2 = p2 + (q1 - p1) * 0.7;  // parallel
        if (trial % 10 == 2) q1 = p1;                    // a point
        if (trial % 10 == 3) q2 = p2;
        if (trial % 10 == 4) p2 = p1 + (q1 - p1) * 0.3, q2 = p1 + (q1 - p1) * 1.4;  // collinear
        const SegmentClosestPoints cp = closestPointsOnSegments(p1, q1, p2, q2);
        ASSERT_GE(cp.s, 0.0);
        ASSERT_LE(cp.s, 1.0);
        ASSERT_GE(cp.t, 0.0);
        ASSERT_LE(cp.t, 1.0);
        EXPECT_NEAR(length(cp.p - (p1 + (q1 - p1) * cp.s)), 0, 1e-12);
        EXPECT_NEAR(length(cp.q - (p2 + (q2 - p2) * cp.t)), 0, 1e-12);
        EXPECT_NEAR(cp.distance, length(cp.p - cp.q), 1e-15);
        double gridMin = kInf;
        for (int i = 0; i <= 100; ++i)
            for (int j = 0; j <= 100; ++j)
                gridMin = std::min(
                    gridMin, length(p1 + (q1 - p1) * (i / 100.0) - p2 - (q2 - p2) * (j / 100.0)));
        EXPECT_LE(cp.distance, gridMin + 1e-12) << "trial " << trial;
    }
}

TEST(CurveReport, MinDistanceEqualsBruteForceOnRandomSets) {
    for (uint64_t seed = 1; seed <= 24; ++seed) {
        // Dense tangles (boxes overlap) and sparse sets of fine segments
        // (boxes apart: the distance pruning decides).
        const CurveSet set = seed % 2
                                 ? randomWalks(seed, 2 + static_cast<int>(seed % 4), 30)
                                 : randomWalks(seed, 4 + static_cast<int>(seed % 9), 60, 12, 0.3);
        const BruteContact truth = bruteForceContact(set);
        const CurveReport report = curveReport(set);
        ASSERT_TRUE(std::isfinite(truth.distance)) << "seed " << seed;
        ASSERT_TRUE(report.closest.has_value()) << "seed " << seed;
        // The same pair: the same numbers, bit for bit.
        EXPECT_EQ(report.closest->distance, truth.distance) << "seed " << seed;
        EXPECT_EQ(report.closest->curveA, truth.curveA) << "seed " << seed;
        EXPECT_EQ(report.closest->curveB, truth.curveB) << "seed " << seed;
        EXPECT_EQ(report.closest->pointA, truth.pointA) << "seed " << seed;
        EXPECT_EQ(report.closest->pointB, truth.pointB) << "seed " << seed;
        EXPECT_EQ(report.largestRadiusWithoutOverlap(), truth.distance / 2);
    }
}

TEST(CurveReport, SelfContactOfOneRandomWalkEqualsBruteForce) {
    int withContact = 0;
    for (uint64_t seed = 11; seed <= 30; ++seed) {
        // In a plane the walk folds back on itself often, at every scale.
        const CurveSet set = randomWalks(seed, 1, 300, 4, seed % 2 ? 0.8 : 0.3, seed % 3 == 0);
        const BruteContact truth = bruteForceContact(set);
        const CurveReport report = curveReport(set);
        ASSERT_EQ(report.closest.has_value(), std::isfinite(truth.distance));
        if (!report.closest) continue;
        ++withContact;
        EXPECT_EQ(report.closest->distance, truth.distance) << "seed " << seed;
        EXPECT_EQ(report.closest->pointA, truth.pointA) << "seed " << seed;
        EXPECT_EQ(report.closest->curveA, 0u);
        EXPECT_EQ(report.closest->curveB, 0u);
    }
    EXPECT_GE(withContact, 15);
}

// An open hairpin whose legs part slowly (0.2 apart at the turn, 0.2 +
// 0.02 x further on), finely divided: the closest contact lies where the
// legs' facing points first become more than twice their distance apart
// along the curve, just where the same-curve pruning is tightest.
TEST(CurveReport, DivergingHairpinMatchesBruteForce) {
    std::vector<Vec3> points;
    for (int k = 200; k > 0; --k) points.push_back({0.01 * k, 0, 0});
    for (int k = 0; k < 16; ++k) {
        const double a = -kHalfPi - kPi * k / 16;
        points.push_back({0.1 * std::cos(a), 0.1 + 0.1 * std::sin(a), 0});
    }
    for (int k = 0; k <= 200; ++k) points.push_back({0.01 * k, 0.2 + 0.0002 * k, 0});
    CurveSet set;
    set.curves.push_back(polyline(points));
    const BruteContact truth = bruteForceContact(set);
    const CurveReport r = curveReport(set);
    ASSERT_TRUE(r.closest.has_value());
    EXPECT_EQ(r.closest->distance, truth.distance);
    EXPECT_EQ(r.closest->pointA, truth.pointA);
    EXPECT_EQ(r.closest->pointB, truth.pointB);
    EXPECT_GT(r.minDistance(), 0.2);
    EXPECT_LT(r.minDistance(), 0.21);
}

// Issue 41: long segments criss-crossing a box made the search quadratic
// (40,000 took 38 s). The segments are now held as pieces; the closest
// contact and the overlap equal brute force on such sets, alone, among the
// short segments of random walks, and with coincident segments.
TEST(CurveReport, LongCrissCrossingSegmentsMatchBruteForce) {
    for (uint64_t seed = 1; seed <= 6; ++seed) {
        const bool walks = seed % 2 == 0;
        const CurveSet set = withRandomSegments(
            walks ? randomWalks(seed, 3, 40, 4, 0.2) : CurveSet{}, seed, walks ? 40 : 90, 4,
            seed % 4 == 3 ? 7 : 0);
        SCOPED_TRACE("seed " + std::to_string(seed));
        const double radius = 0.05;
        const BruteContact truth = bruteForceContact(set);
        const CurveReport report = curveReport(set, radius);
        ASSERT_TRUE(report.closest.has_value());
        EXPECT_EQ(report.closest->distance, truth.distance);
        EXPECT_EQ(report.closest->curveA, truth.curveA);
        EXPECT_EQ(report.closest->curveB, truth.curveB);
        EXPECT_EQ(report.closest->pointA, truth.pointA);
        EXPECT_EQ(report.closest->pointB, truth.pointB);
        const BruteOverlap overlap = bruteForceOverlap(set, radius);
        EXPECT_GT(overlap.fraction, 0.0);
        EXPECT_NEAR(report.overlap->fraction, overlap.fraction, 1e-12);
        EXPECT_EQ(report.overlap->maxDepth, overlap.maxDepth);
        EXPECT_EQ(report.overlap->curvesOverlapping, overlap.curvesOverlapping);
        // The same in the scene's check, whose result per entry is the whole set's.
        const YarnOverlap o = yarnOverlaps({{&set, 1.0, radius}}).front();
        EXPECT_NEAR(o.fraction, overlap.fraction, 1e-12);
        EXPECT_EQ(o.largestRadiusWithoutOverlap, truth.distance / 2);
    }
}

// The searches' work grows about as the input: twice the curves of the same
// kinds (random walks, segments across the box) at the same density (a box
// sqrt(2) times as wide, so that the length per volume stays the same) take
// about as many more steps as there is more length (the segments grow with
// the box; the overlap samples with the length). Held whole (before issue
// 41), each long segment's box overlapped a fixed share of all the others:
// about twice as many steps per length.
TEST(CurveReport, StepsGrowAboutAsTheLengthWithLongSegments) {
    const auto measure = [](int scale) {
        const double box = 20 * std::sqrt(scale);
        const CurveSet set = withRandomSegments(randomWalks(5, 2 * scale, 100, box, 0.5), 6,
                                                150 * scale, box);
        return curveReport(set, 0.2);
    };
    const CurveReport one = measure(1), two = measure(2);
    const double steps = static_cast<double>(two.steps) / static_cast<double>(one.steps);
    const double length = two.totalLength / one.totalLength;
    EXPECT_LT(steps, 1.5 * length) << one.steps << " steps, then " << two.steps;
    EXPECT_GT(length, 2.0);
}

TEST(CurveReport, CountsLengthsAndBounds) {
    CurveSet set;
    set.curves.push_back(polyline({{0, 0, 0}, {3, 0, 0}, {3, 4, 0}}));
    set.curves.push_back(polyline({{0, 0, 1}, {1, 0, 1}, {1, 0, 1}, {1, 1, 1}}, true));
    const CurveReport r = curveReport(set);
    EXPECT_EQ(r.curves, 2u);
    EXPECT_EQ(r.points, 7u);
    EXPECT_EQ(r.closedCurves, 1u);
    EXPECT_EQ(r.segments, 6u);  // 2 open + 4 closed
    EXPECT_EQ(r.degenerateSegments, 1u);
    EXPECT_DOUBLE_EQ(r.totalLength, 3 + 4 + 1 + 0 + 1 + std::sqrt(2.0));
    EXPECT_EQ(r.segmentLengthMin, 0.0);
    EXPECT_EQ(r.segmentLengthMax, 4.0);
    EXPECT_DOUBLE_EQ(r.segmentLengthMean, r.totalLength / 6);
    EXPECT_EQ(r.bounds.lo, (Vec3{0, 0, 0}));
    EXPECT_EQ(r.bounds.hi, (Vec3{3, 4, 1}));
    EXPECT_FALSE(r.overlap.has_value());
}

// Two parallel lines 0.3 apart: every contact distance is 0.3; at R = 0.25
// the whole length is inside the other yarn by (2 R - 0.3) / (2 R) = 0.4.
TEST(CurveReport, TwoParallelLines) {
    CurveSet set;
    set.curves.push_back(straightLine({0, 0, 0}, {10, 0, 0}, 40));
    set.curves.push_back(straightLine({0, 0.3, 0}, {10, 0.3, 0}, 55));
    const CurveReport r = curveReport(set, 0.25);
    ASSERT_TRUE(r.closest.has_value());
    EXPECT_NEAR(r.minDistance(), 0.3, 1e-12);
    EXPECT_NEAR(r.largestRadiusWithoutOverlap(), 0.15, 1e-12);
    EXPECT_EQ(r.closest->curveA, 0u);
    EXPECT_EQ(r.closest->curveB, 1u);
    EXPECT_NEAR(r.closest->pointB.y - r.closest->pointA.y, 0.3, 1e-12);
    ASSERT_TRUE(r.overlap.has_value());
    EXPECT_EQ(r.overlap->radius, 0.25);
    EXPECT_NEAR(r.overlap->fraction, 1.0, 1e-12);
    EXPECT_NEAR(r.overlap->maxDepth, 0.4, 1e-9);
    EXPECT_EQ(r.overlap->curvesOverlapping, 2u);

    const CurveReport thin = curveReport(set, 0.1);
    EXPECT_EQ(thin.overlap->fraction, 0.0);
    EXPECT_EQ(thin.overlap->maxDepth, 0.0);
    EXPECT_EQ(thin.overlap->curvesOverlapping, 0u);

    // The tolerance: overlap starts where 0.3 < 2 R (1 - kOverlapTolerance).
    const double onset = 0.15 / (1 - kOverlapTolerance);
    EXPECT_EQ(curveReport(set, onset * 0.999).overlap->fraction, 0.0);
    EXPECT_NEAR(curveReport(set, onset * 1.001).overlap->fraction, 1.0, 1e-12);
}

// Lines overlapping over half their length: line A on [0, 10], B on [5, 15],
// 0.3 apart. At R = 0.25 a point of A counts while its distance to B is
// below 2 R (1 - tol) = 0.49: for x > 5 - sqrt(0.49^2 - 0.3^2) (B's end is
// the nearest point there), and likewise for B.
TEST(CurveReport, OverlapFractionOfHalfOverlappingLines) {
    CurveSet set;
    set.curves.push_back(straightLine({0, 0, 0}, {10, 0, 0}, 20));
    set.curves.push_back(straightLine({5, 0.3, 0}, {15, 0.3, 0}, 20));
    const double radius = 0.25;
    const CurveReport r = curveReport(set, radius);
    const double reach = std::sqrt(std::pow(2 * radius * (1 - kOverlapTolerance), 2) - 0.09);
    const double expected = 2 * (5 + reach) / 20;
    // Each boundary is resolved to one sample spacing (<= R / 4) of each line.
    EXPECT_NEAR(r.overlap->fraction, expected, 2 * (radius / 4) / 20);
    EXPECT_NEAR(r.overlap->maxDepth, 0.4, 1e-9);
}

// A closed stadium: two sides of length 10, 0.2 apart, joined by half
// circles of radius 0.1. The sides touch each other (points facing each
// other are 2 x + pi 0.1 apart along the loop, more than 2 x 0.2 but for x <
// 0.043 of the ends); across a half circle sep / distance <= pi / 2: no contact.
TEST(CurveReport, ClosedLoopThatTouchesItself) {
    std::vector<Vec3> points;
    const int sidePoints = 200, arcPoints = 16;
    const double half = 0.1;
    for (int k = 0; k < sidePoints; ++k) points.push_back({10.0 * k / sidePoints, 0, 0});
    for (int k = 0; k < arcPoints; ++k) {
        const double a = -kHalfPi + kPi * k / arcPoints;
        points.push_back({10 + half * std::cos(a), half + half * std::sin(a), 0});
    }
    for (int k = 0; k < sidePoints; ++k)
        points.push_back({10 - 10.0 * k / sidePoints, 2 * half, 0});
    for (int k = 0; k < arcPoints; ++k) {
        const double a = kHalfPi + kPi * k / arcPoints;
        points.push_back({half * std::cos(a), half + half * std::sin(a), 0});
    }
    CurveSet set;
    set.curves.push_back(polyline(points, true));
    const double radius = 0.15;
    const CurveReport r = curveReport(set, radius);
    ASSERT_TRUE(r.closest.has_value());
    EXPECT_NEAR(r.minDistance(), 0.2, 1e-12);
    EXPECT_EQ(r.closest->curveA, 0u);
    EXPECT_EQ(r.closest->curveB, 0u);
    EXPECT_EQ(r.closedCurves, 1u);
    // At R = 0.15 the sides overlap, but not near the turns: a point x from
    // the end of a side has facing partners x' from the turn's end only
    // 2 R (1 - tol) = 0.294 away and more than 4 R along the loop, x + turn +
    // x' > 4 R. So all of a side beyond x = (4 R - turn) / 2 overlaps (x' =
    // x, 0.2 away), nothing closer than x = (4 R - turn - sqrt(0.294^2 -
    // 0.2^2)) / 2 does; each boundary to one sample spacing (0.025).
    const double turn = arcPoints * 2 * half * std::sin(kHalfPi / arcPoints);
    const double reach = std::sqrt(std::pow(2 * radius * (1 - kOverlapTolerance), 2) - 0.04);
    const double total = r.totalLength, spacing = 0.025;
    EXPECT_NEAR(total, 20 + 2 * turn, 1e-9);
    EXPECT_GE(r.overlap->fraction, (20 - 4 * ((4 * radius - turn) / 2 + spacing)) / total);
    EXPECT_LE(r.overlap->fraction, (20 - 4 * ((4 * radius - turn - reach) / 2 - spacing)) / total);
    EXPECT_NEAR(r.overlap->maxDepth, (0.3 - 0.2) / 0.3, 1e-9);
    EXPECT_EQ(r.overlap->curvesOverlapping, 1u);
}

// A plain circle never touches itself: points theta apart are
// 2 sin(theta / 2) apart and theta > 4 sin(theta / 2) nowhere in (0, pi].
TEST(CurveReport, PlainCircleHasNoContact) {
    std::vector<Vec3> points;
    for (int k = 0; k < 400; ++k)
        points.push_back({std::cos(kTwoPi * k / 400), std::sin(kTwoPi * k / 400), 0});
    CurveSet set;
    set.curves.push_back(polyline(points, true));
    for (double radius : {0.1, 0.5, 0.9}) {
        const CurveReport r = curveReport(set, radius);
        EXPECT_FALSE(r.closest.has_value());
        EXPECT_EQ(r.largestRadiusWithoutOverlap(), kInf);
        EXPECT_EQ(r.overlap->fraction, 0.0) << "radius " << radius;
    }
}

TEST(CurveReport, StraightLineHasNoContact) {
    CurveSet set;
    set.curves.push_back(straightLine({0, 0, 0}, {100, 10, 5}, 20000));
    const CurveReport r = curveReport(set, 1.0);
    EXPECT_FALSE(r.closest.has_value());
    EXPECT_EQ(r.overlap->fraction, 0.0);
    const nlohmann::json j = toJson(r);
    EXPECT_TRUE(j.at("min_distance").is_null());
    EXPECT_TRUE(j.at("largest_radius_without_overlap").is_null());
    EXPECT_TRUE(j.at("closest").is_null());
}

TEST(CurveReport, JsonKeys) {
    CurveSet set;
    set.curves.push_back(straightLine({0, 0, 0}, {10, 0, 0}, 4));
    set.curves.push_back(straightLine({0, 0.3, 0}, {10, 0.3, 0}, 4));
    const nlohmann::json j = toJson(curveReport(set, 0.25));
    for (const char* key : {"curves", "points", "closed_curves", "basis", "segments",
                            "degenerate_segments", "total_length", "bounds", "segment_length",
                            "min_distance", "closest", "largest_radius_without_overlap", "overlap"})
        EXPECT_TRUE(j.contains(key)) << key;
    EXPECT_EQ(j.at("basis"), "polyline");
    EXPECT_NEAR(j.at("min_distance").get<double>(), 0.3, 1e-12);
    EXPECT_EQ(j.at("closest").at("curves"), nlohmann::json({0, 1}));
    EXPECT_EQ(j.at("overlap").at("radius"), 0.25);
    EXPECT_NEAR(j.at("overlap").at("max_overlap").get<double>(), 0.4, 1e-9);
    EXPECT_EQ(j.at("overlap").at("curves_overlapping"), 2);
    EXPECT_TRUE(toJson(curveReport(set)).at("overlap").is_null());
}

TEST(CurveReport, RadiusMustBeFiniteAndPositive) {
    CurveSet set;
    set.curves.push_back(straightLine({0, 0, 0}, {1, 0, 0}, 1));
    for (double bad : {0.0, -1.0, std::nan(""), kInf})
        expectInputError([&] { curveReport(set, bad); }, {"radius", "finite and > 0"});
    expectInputError([] { checkOverlapRadius(-2, "--radius"); }, {"--radius -2", "> 0"});
}

// A scene's yarn entries: positions scaled, pairs across entries counted, and
// each entry's depth measured in its own diameter.
TEST(YarnOverlaps, ParallelYarnsOfTwoEntries) {
    CurveSet a, b;
    a.curves.push_back(straightLine({0, 0, 0}, {10, 0, 0}, 10));
    b.curves.push_back(straightLine({0, 3, 0}, {100, 3, 0}, 10));  // scale 0.1: 0.3 from a
    std::vector<YarnOverlap> o = yarnOverlaps({{&a, 1.0, 0.25}, {&b, 0.1, 0.25}});
    ASSERT_EQ(o.size(), 2u);
    for (const YarnOverlap& y : o) {
        EXPECT_EQ(y.radius, 0.25);
        EXPECT_NEAR(y.fraction, 1.0, 1e-12);
        EXPECT_NEAR(y.maxDepth, 0.4, 1e-9);
        EXPECT_NEAR(y.largestRadiusWithoutOverlap, 0.15, 1e-12);
    }
    // Radii 0.1 and 0.25: the yarns interpenetrate by 0.35 - 0.3 = 0.05,
    // a quarter of the thin yarn's diameter and a tenth of the thick one's.
    o = yarnOverlaps({{&a, 1.0, 0.1}, {&b, 0.1, 0.25}});
    EXPECT_NEAR(o[0].maxDepth, 0.25, 1e-9);
    EXPECT_NEAR(o[1].maxDepth, 0.1, 1e-9);
    EXPECT_NEAR(o[0].fraction, 1.0, 1e-12);
    // Far apart: no overlap, and no contact within either entry.
    o = yarnOverlaps({{&a, 1.0, 0.1}, {&b, 1.0, 0.1}});
    EXPECT_EQ(o[0].fraction, 0.0);
    EXPECT_NEAR(o[0].largestRadiusWithoutOverlap, 1.5, 1e-12);
    EXPECT_EQ(yarnOverlaps({{&a, 1.0, 0.1}})[0].largestRadiusWithoutOverlap, kInf);
}

// Per entry, the smallest contact distance involving it, against brute force.
TEST(YarnOverlaps, LargestRadiusPerEntryEqualsBruteForce) {
    const CurveSet first = randomWalks(21, 2, 25);
    CurveSet second = randomWalks(22, 2, 25);
    for (Curve& c : second.curves)
        for (Vec3& p : c.points) p += Vec3{3, 0, 0};
    CurveSet both = first;
    for (const Curve& c : second.curves) both.curves.push_back(c);
    const std::vector<YarnOverlap> o = yarnOverlaps({{&first, 1.0, 0.1}, {&second, 1.0, 0.1}});
    // Brute force over the union: curves 0 and 1 are the first entry's. (The
    // two entries' closest contacts differ: the second's lies within it.)
    EXPECT_NE(o[0].largestRadiusWithoutOverlap, o[1].largestRadiusWithoutOverlap);
    for (size_t e = 0; e < 2; ++e) {
        const auto involves = [e](size_t a, size_t b) {
            return (a >= 2) == (e == 1) || (b >= 2) == (e == 1);
        };
        EXPECT_EQ(o[e].largestRadiusWithoutOverlap, bruteForceContact(both, involves).distance / 2);
    }
}

TEST(YarnOverlaps, WarningNamesTheEntryTheFractionAndTheRadius) {
    YarnOverlap o;
    o.radius = 0.25;
    o.fraction = 0.247;
    o.maxDepth = 0.7;
    o.largestRadiusWithoutOverlap = 0.075;
    EXPECT_EQ(yarnOverlapWarning("knit/scene.json", 1, "knit.bcc", o),
              "knit/scene.json: yarns[1] (knit.bcc): 24.7% of the yarn length lies inside other "
              "yarns (up to 70% of the diameter) at radius 0.25; the largest radius without "
              "overlap is 0.075");
    o.fraction = 0;
    EXPECT_EQ(yarnOverlapWarning("scene.json", 0, "a.txt", o), "");
    // Issue 43, item 7: a yarn far thinner than its curves allow (units?).
    o.radius = 0.001;
    EXPECT_EQ(yarnOverlapWarning("scene.json", 0, "a.txt", o),
              "scene.json: yarns[0] (a.txt): the yarns cover little of the space between the "
              "curves: radius 0.001 is 1.3% of the largest radius without overlap, 0.075 (curve "
              "units or scale wrong? docs/curves.md, \"Choosing a radius and a scale\")");
    o.radius = kThinYarnFraction * 0.075;
    EXPECT_EQ(yarnOverlapWarning("scene.json", 0, "a.txt", o), "");
    o.largestRadiusWithoutOverlap = std::numeric_limits<double>::infinity();
    o.radius = 1e-9;
    EXPECT_EQ(yarnOverlapWarning("scene.json", 0, "a.txt", o), "");
    o.radius = 0.25;
    o.largestRadiusWithoutOverlap = 0.075;
    const nlohmann::json j = toJson(o, 2, "a.txt");
    EXPECT_EQ(j.at("yarn"), 2);
    EXPECT_EQ(j.at("curves"), "a.txt");
    EXPECT_EQ(j.at("overlap_fraction"), 0.0);
    EXPECT_EQ(j.at("largest_radius_without_overlap"), 0.075);
}

// The shared real knit: the search against brute force on real data.
TEST(CurveReportSharedData, KnitMatchesBruteForce) {
    const std::string file = std::string(WEFT_CURVE_DATA_DIR) + "/knit-stockinette-tiny.bcc";
    if (!std::filesystem::exists(file)) GTEST_SKIP() << file << " is missing";
    const CurveSet set = readCurves(file);
    const CurveReport r = curveReport(set, 1.0);
    const BruteContact truth = bruteForceContact(set);
    ASSERT_TRUE(r.closest.has_value());
    EXPECT_EQ(r.closest->distance, truth.distance);
    EXPECT_EQ(r.closest->curveA, truth.curveA);
    EXPECT_EQ(r.closest->curveB, truth.curveB);
    EXPECT_EQ(r.segments, 804u);
}

}  // namespace
}  // namespace weft::render
