// weft/render/curve_report.h — what a set of yarn curves is, and whether its
// yarns interpenetrate at a radius (issue 22; `weft curves info`, the overlap
// warning of `weft render` and `weft scene`, docs/curves.md).
//
// Imported yarn-level models rarely say which yarn radius they were made for.
// This file measures the curves themselves: counts, lengths, the box, the
// segment lengths, the closest approach of two yarns and, for a radius R, how
// much of the yarn length lies inside another yarn.
//
// Geometry. Every curve is analysed as its polyline: the straight segments
// between consecutive control points, plus the closing segment of a closed
// curve. A Catmull-Rom curve (BCC "C0") is analysed on its control polygon,
// not on the spline (the spline passes through the control points and stays
// close to the polygon where the points are dense; docs/curves.md). Arc
// positions are measured along that polyline.
//
// Contact. Two points p (curve i, arc position a) and q (curve j, arc position
// b) are in contact when i != j, or when i == j and they are farther apart
// along the curve than twice their distance,
//     sep(a, b) > 2 |p - q|,   sep = |a - b|, or min(|a - b|, L - |a - b|)
//                              on a closed curve of length L (the shorter way),
// i.e. with R = |p - q| / 2 they are more than 4 R apart along the curve: a
// few radii. Neighbouring points of one smooth curve are never in contact
// (there sep ~ |p - q|); a loop that comes back to touch itself is. For two
// segments the rule is evaluated at their closest points (s, t of
// closestPointsOnSegments).
//   minDistance = the smallest |p - q| over contact pairs;
//   largestRadiusWithoutOverlap = minDistance / 2: for every R up to it no
//   contact pair (at radius R: other curve, or same curve more than 4 R apart
//   along it) is closer than 2 R, and just above it the closest pair
//   overlaps. (Because the same-curve rule depends on R, a larger radius can
//   be free of overlap again, e.g. when a tight hairpin drops out of the
//   4 R window; the value is the end of the first overlap-free interval.)
//   Infinite when there is no contact pair at all (one straight line, one
//   plain circle: on a circle sep / |p - q| <= pi / 2 < 2).
// The search is exact and uses a bounding volume hierarchy over the segments,
// traversed against itself; a pair of nodes is skipped when its boxes are
// farther apart than the best pair so far, when they are as far apart and
// cannot hold an earlier pair in segment order (so that many pairs at one
// distance, e.g. coincident segments, cost no more than one), or when both
// hold one stretch of the same curve that is too short along the curve for
// any contact (max sep <= 2 x box distance), so that one long yarn with no
// contact costs O(n log n), not all pairs. A segment longer than the
// spacing its set would have spread evenly over its box (sqrt(D^3 / L), D
// the box's diagonal, L the total length) is held as several pieces of about
// that length (at most 32 per segment on average and 2^21 in all), so that
// long segments criss-crossing a box do not all overlap (issue 41); the
// searches still measure whole segments. Yarn curves are held whole. Every
// search is bounded (kMaxReportStepsPerItem), and its memory is checked
// against the budget (core/limits.h) before it is allocated.
//
// Overlap at radius R. Each segment is sampled at spacing <= R / 4 (at least
// both ends; at most kMaxSamplesPerSegment intervals), each sample weighted by
// the length it stands for (trapezoid weights). For a sample x the partner
// segments are those of other curves and those of its own curve whose closest
// point to x is more than 4 R away along the curve; with d the distance from
// x to the nearest partner the interpenetration is 2 R - d, and x overlaps
// when (2 R - d) / (2 R) > kOverlapTolerance. Reported: the overlapping
// length over the total length, the largest (2 R - d) / (2 R) (a fraction of
// the diameter: 1 = the centre lines cross), and how many curves overlap.
// For the yarns of a scene (yarnOverlaps) the radii may differ: x on a yarn of
// radius R_i against a partner of radius R_j interpenetrates by
// R_i + R_j - d, reported as a fraction of x's diameter 2 R_i, and pairs
// across yarn entries count as well.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "weft/core/curves.h"
#include "weft/core/error.h"
#include "weft/core/vec.h"

namespace weft::render {

// Interpenetration below 2% of the diameter is not counted as overlap: curves
// written with float32 coordinates, or yarns meant to touch (the generated
// weave and knit leave 1-2% clearance, docs/scenes.md), stay silent.
inline constexpr double kOverlapTolerance = 0.02;
// A segment longer than this many times R / 4 is sampled more coarsely, which
// bounds the work for a radius far below the segment lengths.
inline constexpr int kMaxSamplesPerSegment = 1024;
// Each search (the closest contact; the overlap samples) stops after
// kMaxReportStepsPerItem steps (a node of the hierarchy visited, a segment
// pair measured) per segment and per overlap sample, and never before
// kMinReportSteps, with a CurveReportLimit: its time is bounded for any
// input, in proportion to its size. Yarn curves take 10 to 80 steps per
// item (the shared knit and satin, random walks; bench/curves); a tangle of
// long segments criss-crossing a box (thousands of steps per segment) is
// refused (docs/limits.md).
inline constexpr uint64_t kMaxReportStepsPerItem = 256;
inline constexpr uint64_t kMinReportSteps = 100'000'000;

// The InputError of a search that reached its step limit.
class CurveReportLimit : public InputError {
  public:
    using InputError::InputError;
};

// Closest points of segments [p1, q1] and [p2, q2]: p = p1 + s (q1 - p1),
// q = p2 + t (q2 - p2), s and t in [0, 1] (Ericson, Real-Time Collision
// Detection, 5.1.9; parallel segments take s = 0 unless clamped). Exposed for
// the tests' brute-force searches.
struct SegmentClosestPoints {
    double s = 0, t = 0;
    Vec3 p, q;
    double distance = 0;
};
SegmentClosestPoints closestPointsOnSegments(const Vec3& p1, const Vec3& q1, const Vec3& p2,
                                             const Vec3& q2);

// The closest contact pair of a curve set.
struct CurveContact {
    double distance = 0;
    size_t curveA = 0, curveB = 0;  // curve indices, curveA <= curveB (equal: a self-contact)
    Vec3 pointA, pointB;            // on curveA and curveB
};

// Overlap at one radius (see above).
struct CurveOverlap {
    double radius = 0;
    double fraction = 0;  // overlapping length / total length, [0, 1]
    double maxDepth = 0;  // largest interpenetration / diameter over overlapping samples
    size_t curvesOverlapping = 0;
};

struct CurveReport {
    size_t curves = 0, points = 0, closedCurves = 0;
    CurveBasis basis = CurveBasis::Polyline;
    size_t segments = 0, degenerateSegments = 0;  // degenerate: zero length
    double totalLength = 0;
    Bounds3 bounds;  // around the control points
    double segmentLengthMin = 0, segmentLengthMean = 0, segmentLengthMax = 0;
    std::optional<CurveContact> closest;  // none: no contact pair
    std::optional<CurveOverlap> overlap;  // when a radius was given
    // The steps the searches took (kMaxReportStepsPerItem), not in the JSON.
    uint64_t steps = 0;

    double minDistance() const {
        return closest ? closest->distance : std::numeric_limits<double>::infinity();
    }
    double largestRadiusWithoutOverlap() const { return 0.5 * minDistance(); }
};

// InputError "<label> <r> is out of range: allowed finite and > 0" unless it is.
void checkOverlapRadius(double radius, const std::string& label);

// The report of `set` (in its own units), with the overlap at `radius` when
// given (checked by checkOverlapRadius with label "radius"). A search past
// its step limit throws CurveReportLimit, its message beginning with `name`
// (the file).
CurveReport curveReport(const CurveSet& set, std::optional<double> radius = std::nullopt,
                        const std::string& name = "curves");

// The report as JSON: curves, points, closed_curves, basis ("polyline",
// "catmull_rom"), segments, degenerate_segments, total_length, bounds {min,
// max}, segment_length {min, mean, max}, min_distance, closest {curves,
// points} and largest_radius_without_overlap (null without a contact pair),
// overlap {radius, fraction, max_overlap, curves_overlapping} (null without a
// radius).
nlohmann::json toJson(const CurveReport& report);

// The yarns of a scene: each entry's curves, scaled into scene units, and its
// radius in scene units.
struct YarnCurves {
    const CurveSet* curves = nullptr;
    double scale = 1;
    double radius = 0;  // finite, > 0
};

struct YarnOverlap {
    double radius = 0;
    double fraction = 0;  // of this entry's length inside any yarn (its own included)
    double maxDepth = 0;  // fraction of this entry's diameter
    // Half the smallest contact distance involving this entry (infinite: none).
    double largestRadiusWithoutOverlap = std::numeric_limits<double>::infinity();

    bool overlaps() const { return fraction > 0; }
};

// Overlap of every entry against all of them (one result per entry, in order);
// `name` begins a CurveReportLimit's message (the scene).
std::vector<YarnOverlap> yarnOverlaps(const std::vector<YarnCurves>& yarns,
                                      const std::string& name = "yarns");

// A yarn thinner than this share of its largest radius without overlap
// leaves most of the space between its curves empty: weft render and weft
// scene warn (a unit mistake, the yarn 100 times too thin, renders an almost
// empty image). The generated weave and knit sit at about 1.
inline constexpr double kThinYarnFraction = 0.1;
// A closing segment this many times longer than its curve's mean segment is
// named when it makes the largest radius 0 (zeroRadiusExplanation).
inline constexpr double kLongClosingSegment = 10;

// Why `report` (of `set`) has a largest radius without overlap of 0 or near
// it: the curves and the point of its closest contact, and, when a closed
// curve's closing segment there is more than kLongClosingSegment times its
// curve's other segments, that: often an open yarn written as closed.
std::string zeroRadiusExplanation(const CurveSet& set, const CurveReport& report);

// The warning for one scene entry, without the "weft: warning: " prefix, or ""
// when it neither overlaps nor is far too thin:
//   <scene>: yarns[i] (<curves>): 24.7% of the yarn length lies inside other
//   yarns (up to 70% of the diameter) at radius 0.25; the largest radius
//   without overlap is 0.075
//   <scene>: yarns[i] (<curves>): the yarns cover little of the space between
//   the curves: radius 0.001 is 1.3% of the largest radius without overlap,
//   0.075 (...)
std::string yarnOverlapWarning(const std::string& scene, size_t yarn, const std::string& curves,
                               const YarnOverlap& overlap);

// {"yarn": i, "curves": path, "radius", "overlap_fraction", "max_overlap",
//  "largest_radius_without_overlap" (null when infinite)}.
nlohmann::json toJson(const YarnOverlap& overlap, size_t yarn, const std::string& curves);

}  // namespace weft::render
