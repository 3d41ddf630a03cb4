// weft/render/yarn_geometry.h — from a yarn centre line to plies and fibers (issue 7).
//
// A yarn curve (render/curves.h) is drawn either as k plies (neural mode: each
// ply is one tube shaded with the yarn BSDF) or as the fibers of those plies
// (fiber mode: each fiber is one tube shaded with the fiber BCSDF), docs/design.md 8.
//
// 1. frameCurve samples the centre line (a uniform Catmull-Rom spline is
//    evaluated; polyline spans are split) so that no sample spacing exceeds
//    maxStep, and propagates a rotation-minimising frame (T, N, B = T x N)
//    along it by the double reflection method (Wang, Juettler, Zheng, Liu
//    2008, "Computation of rotation minimizing frames"). On a closed curve
//    the frame that comes back to the start is turned by some angle (the
//    curve's holonomy); that angle is spread linearly over the arc length so
//    that the frame, and every helix built on it, has no seam.
//    Catmull-Rom: tension 0.5, one span per pair of neighbouring control
//    points; an open curve's missing end neighbours are the reflected points
//    P_-1 = 2 P_0 - P_1 and P_n = 2 P_n-1 - P_n-2 (the end spans then start
//    and end with the chord's direction and no overshoot); a closed curve
//    wraps around. Each span is split uniformly in its parameter into
//    ceil(bound / maxStep) pieces, bound = the largest length of the three
//    control points of the span's (quadratic Bezier) hodograph, which bounds
//    the speed |p'(t)| and so the arc length of every piece. Per-point radii
//    are interpolated linearly in the span parameter u, per-point colours
//    (Curve::colours) too but with u rounded to a multiple of
//    1 / kColourSteps: a sample's colour is a material (render/scene.h), so
//    a colour change between two control points makes at most
//    kColourSteps - 1 colours between them, and a run of control points of
//    one colour stays exactly that colour. T is the analytic
//    spline derivative (Catmull-Rom) or, on polylines, the derivative of the
//    parabola through a sample and its two neighbours at chord-length spacing
//    (exact on circles). The first normal is coordinateSystem(T_0) (core/vec.h:
//    T = +z gives N = +x, B = +y, the axes of ply/ply.h).
// 2. plyCurves wraps k plies around the yarn: ply j's centre is
//        c_j(s) = p(s) + (R(s) - R_ply(s)) (cos theta_j(s) N(s) + sin theta_j(s) B(s)),
//        theta_j(s) = 2 pi j / k + integral_0^s pi ply_twist / R(u) du
//    (right-handed about T for ply_twist > 0, like the fibers of docs/design.md 4;
//    left-handed for ply_twist < 0), R_ply = R sin(pi/k) / (1 + sin(pi/k)) for
//    k >= 2 and R for k = 1, so that the plies touch each other and the yarn
//    surface. On a closed curve ply_twist is rounded so that the total turn
//    is a whole multiple 2 pi m / k (m != 0 when ply_twist != 0, with its
//    sign): ply j then continues as ply j + m after one loop, so the k plies
//    form g = gcd(|m|, k) closed curves of k / g loops each (g = k, one loop
//    per ply, when m is a multiple of k). Each ply centre line gets its own
//    rotation-minimising frame.
// 3. fiberTubes fills one ply with the fibers of the model's ply block: the
//    fiber centres of generatePly (ply/ply.h, the generator the gather uses)
//    at radius R_ply, turned about the ply's T by pi alpha s / R_ply (the
//    right-handed twist of docs/design.md 4, with N and B standing for x and y),
//    scaled with R_ply(s) / R_ply(0) where the radius varies (the turn is
//    then integral_0^s pi alpha / R_ply(u) du). On a closed ply alpha is
//    rounded so that the loop makes a whole number m of turns (m >= 1 when
//    alpha > 0), so that every fiber closes on itself.
//
// Lengths are scene units (positions times the yarn's scale). The maths in
// prose, with the closed-curve rounding rules: docs/render-geometry.md.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "weft/core/curves.h"
#include "weft/core/rgb.h"
#include "weft/core/vec.h"
#include "weft/ply/ply.h"

namespace weft::render {

// Steps of a colour change between two control points (above).
inline constexpr int kColourSteps = 16;

// A centre line with a radius per point: what Embree draws as one round
// linear curve (cones joined by spheres). A closed tube's last point joins
// its first (the first point is not repeated).
struct Tube {
    std::vector<Vec3> points;  // >= 2
    std::vector<float> radii;  // one per point, > 0
    bool closed = false;

    size_t segmentCount() const { return closed ? points.size() : points.size() - 1; }
};

// A densely sampled centre line with a rotation-minimising frame per sample.
struct FramedCurve {
    std::vector<Vec3> points;
    std::vector<Vec3> tangents;     // unit
    std::vector<Vec3> normals;      // unit, orthogonal to the tangent
    std::vector<Vec3> binormals;    // tangent x normal
    std::vector<double> arcLength;  // from the first sample (0) along the polyline
    std::vector<double> radius;     // > 0
    // C_TT per sample, interpolated like the radius; empty when the curve has no colours.
    std::vector<Rgb> colours;
    bool closed = false;
    double length = 0;  // total polyline length, closing segment included
    // Closed curves: the angle (radians, right-handed about T_0, in [-pi, pi])
    // by which the double-reflection frame came back turned after one loop;
    // the normals are turned by -holonomy s / L to close it. 0 when open.
    double holonomy = 0;

    size_t size() const { return points.size(); }
};

// Upper bound on the samples of one framed curve (a memory guard: frameCurve
// throws InputError rather than allocate more).
inline constexpr int64_t kMaxCurveSamples = int64_t{1} << 26;

// Samples and frames `curve` (positions times scale). radius: the tube radius
// everywhere; absent: the curve's per-point radii times scale (InputError
// naming `source` and the curve index if it has none). Consecutive
// coincident control points are dropped (closer than 1e-12 times the
// curve's extent; on a closed curve also a last point equal to the first);
// a curve with fewer than 2 distinct points (3 when closed) is an InputError
// naming `source` and the curve index, as are a scale or radius that is not
// finite and > 0, and more than kMaxCurveSamples samples. maxStep: finite,
// > 0 (std::invalid_argument otherwise: a caller bug).
FramedCurve frameCurve(const Curve& curve, double scale, std::optional<double> radius,
                       double maxStep, const std::string& source, size_t curveIndex);

// R_ply for k plies in a yarn of radius R (above). InputError unless k >= 1, R > 0.
double plyRadius(double yarnRadius, int plies);

// The k ply centre lines of a framed yarn (above), each framed, with R_ply per
// point; ply j of an open yarn is element j and shares the yarn's sample
// indices. A closed yarn gives gcd(|m|, k) closed curves (above), whose
// sample lap * n + i lies beside the yarn's sample i. k = 1 is the yarn
// itself. The plies take the yarn's colours sample by sample. InputError unless plies >= 1 and
// plyTwist is finite.
std::vector<FramedCurve> plyCurves(const FramedCurve& yarn, int plies, double plyTwist);

// The curve as one tube (neural mode).
Tube toTube(const FramedCurve& curve);

// The fibers of one ply (fiber mode), from the fiber layout of
// generatePly(params, R_ply(0), ..., seed). Fiber radius r = R_ply sqrt(rho / N).
std::vector<Tube> fiberTubes(const FramedCurve& ply, const PlyParams& params, uint64_t seed);

// Largest sample spacing for frameCurve so that every helix is resolved with
// at least `pointsPerTwist` points per turn, and never more than R / 4:
//   min(R / 4, P_ply / n, [fiber mode] P_fiber / (n stretch)),
//   P_ply = 2 R / |ply_twist| (infinite for 0), P_fiber = 2 R_ply / alpha
//   (infinite for 0), stretch = sqrt(1 + (pi ply_twist (R - R_ply) / R)^2):
// a ply is longer than the yarn by that factor on a straight yarn, and its
// fibers twist per unit of ply length. fibers == nullptr: neural mode. For a
// curve with varying radius pass its smallest radius. InputError unless
// R is finite and > 0, plies >= 1, plyTwist finite and *fibers valid;
// pointsPerTwist >= 1 (std::invalid_argument otherwise).
double sampleStep(double yarnRadius, int plies, double plyTwist, const PlyParams* fibers,
                  int pointsPerTwist = 32);

}  // namespace weft::render
