#include "weft/render/yarn_geometry.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/math.h"
#include "weft/core/test_util.h"

namespace weft::render {
namespace {

using weft::testing::expectInputError;

Curve makeCurve(std::vector<Vec3> points, CurveBasis basis, bool closed = false) {
    Curve c;
    c.points = std::move(points);
    c.basis = basis;
    c.closed = closed;
    return c;
}

FramedCurve frame(const Curve& c, double radius, double maxStep) {
    return frameCurve(c, 1.0, radius, maxStep, "test.bcc", 0);
}

// Points t -> f(t) for t = t0 + i (t1 - t0) / (count - 1), or / count when the
// curve is closed (the end point is not repeated).
template <typename F>
std::vector<Vec3> sampled(const F& f, double t0, double t1, int count, bool closed = false) {
    std::vector<Vec3> pts;
    const int div = closed ? count : count - 1;
    for (int i = 0; i < count; ++i) pts.push_back(f(t0 + (t1 - t0) * i / div));
    return pts;
}

void expectOrthonormalFrames(const FramedCurve& c) {
    ASSERT_EQ(c.tangents.size(), c.size());
    ASSERT_EQ(c.normals.size(), c.size());
    ASSERT_EQ(c.binormals.size(), c.size());
    for (size_t i = 0; i < c.size(); ++i) {
        EXPECT_NEAR(length(c.tangents[i]), 1.0, 1e-12) << i;
        EXPECT_NEAR(length(c.normals[i]), 1.0, 1e-12) << i;
        EXPECT_NEAR(dot(c.tangents[i], c.normals[i]), 0.0, 1e-12) << i;
        EXPECT_NEAR(length(c.binormals[i] - cross(c.tangents[i], c.normals[i])), 0.0, 1e-12) << i;
    }
}

// Angular velocity of the frame about T on each segment (closing one last):
// dot(dN/ds, B) by a symmetric difference, O(h^2) off the continuous value.
std::vector<double> twistRates(const FramedCurve& c) {
    std::vector<double> w;
    const size_t n = c.size();
    const size_t segments = c.closed ? n : n - 1;
    for (size_t i = 0; i < segments; ++i) {
        const size_t j = (i + 1) % n;
        const double h = length(c.points[j] - c.points[i]);
        w.push_back(dot(c.normals[j] - c.normals[i], 0.5 * (c.binormals[i] + c.binormals[j])) / h);
    }
    return w;
}

double maxAbs(const std::vector<double>& v) {
    double m = 0;
    for (double x : v) m = std::max(m, std::abs(x));
    return m;
}

// ---------------------------------------------------------------------------
// Sampling

// The samples of a Catmull-Rom curve are the spline of the header's formula,
// with reflected end neighbours, at uniform parameters within each span.
TEST(FrameCurve, CatmullRomFollowsTheSplineFormulaWithReflectedEnds) {
    const std::vector<Vec3> p = {{0, 0, 0}, {1, 0.5, 0}, {2, -0.3, 0.4}, {2.5, 1, 1}, {4, 1, 0}};
    const FramedCurve c = frame(makeCurve(p, CurveBasis::CatmullRom), 0.1, 0.05);
    const auto formula = [](const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3,
                            double t) {
        return 0.5 * (2.0 * p1 + (p2 - p0) * t + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t * t +
                      (-1.0 * p0 + 3.0 * p1 - 3.0 * p2 + p3) * t * t * t);
    };
    const size_t n = p.size();
    const auto ctrl = [&](int j) {
        if (j < 0) return 2.0 * p[0] - p[1];
        if (j >= static_cast<int>(n)) return 2.0 * p[n - 1] - p[n - 2];
        return p[static_cast<size_t>(j)];
    };
    // Every control point is a sample; the samples between two of them are
    // the span at t = j / m.
    std::vector<size_t> at;
    for (const Vec3& q : p) {
        size_t best = 0;
        for (size_t i = 0; i < c.size(); ++i)
            if (length(c.points[i] - q) < length(c.points[best] - q)) best = i;
        EXPECT_LT(length(c.points[best] - q), 1e-15);
        at.push_back(best);
    }
    EXPECT_EQ(at.front(), 0u);
    EXPECT_EQ(at.back(), c.size() - 1);
    for (size_t k = 0; k + 1 < n; ++k) {
        const size_t m = at[k + 1] - at[k];
        ASSERT_GE(m, 1u);
        const int j = static_cast<int>(k);
        for (size_t i = 0; i <= m; ++i) {
            const double t = static_cast<double>(i) / m;
            const Vec3 expected = formula(ctrl(j - 1), ctrl(j), ctrl(j + 1), ctrl(j + 2), t);
            EXPECT_LT(length(c.points[at[k] + i] - expected), 1e-12) << "span " << k << " t " << t;
        }
    }
    // The reflected end neighbour makes the end tangents the end chords.
    EXPECT_LT(length(c.tangents.front() - normalize(p[1] - p[0])), 1e-12);
    EXPECT_LT(length(c.tangents.back() - normalize(p[n - 1] - p[n - 2])), 1e-12);
    for (size_t i = 0; i + 1 < c.size(); ++i)
        EXPECT_LE(length(c.points[i + 1] - c.points[i]), 0.05) << i;
    expectOrthonormalFrames(c);
}

TEST(FrameCurve, ClosedCatmullRomWrapsAround) {
    // Four points on a circle: the closed spline is symmetric under a quarter turn.
    const std::vector<Vec3> p = {{1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
    const FramedCurve c = frame(makeCurve(p, CurveBasis::CatmullRom, true), 0.05, 0.01);
    ASSERT_EQ(c.size() % 4, 0u);
    const size_t q = c.size() / 4;
    for (size_t i = 0; i < q; ++i) {
        const Vec3 a = c.points[i], b = c.points[i + q];
        EXPECT_LT(length(Vec3(-a.y, a.x, 0) - b), 1e-12) << i;  // turned by 90 degrees
    }
    // Closed: the first point is not repeated, the closing segment is short.
    EXPECT_GT(length(c.points.back() - c.points.front()), 0.0);
    EXPECT_LE(length(c.points.back() - c.points.front()), 0.01);
    EXPECT_NEAR(c.length, c.arcLength.back() + length(c.points.back() - c.points.front()), 1e-12);
    // Wrapping neighbours: the tangent at a control point is (P_{i+1} - P_{i-1}) / 2.
    EXPECT_LT(length(c.tangents[0] - Vec3(0, 1, 0)), 1e-12);
}

TEST(FrameCurve, PolylineSpansAreSplitEvenlyWithLinearRadii) {
    Curve curve = makeCurve({{0, 0, 0}, {1, 0, 0}, {1, 2.5, 0}}, CurveBasis::Polyline);
    curve.radii = {0.1f, 0.2f, 0.4f};
    const FramedCurve c = frameCurve(curve, 2.0, std::nullopt, 0.6, "x.txt", 0);
    // Scaled lengths 2 and 5: ceil(2 / 0.6) = 4 and ceil(5 / 0.6) = 9 pieces.
    ASSERT_EQ(c.size(), 14u);
    EXPECT_NEAR(c.length, 7.0, 1e-12);
    for (size_t i = 0; i <= 4; ++i) {
        EXPECT_NEAR(c.points[i].x, 2.0 * i / 4.0, 1e-12);
        EXPECT_NEAR(c.radius[i], 2.0 * (0.1 + 0.1 * i / 4.0), 1e-7);
        EXPECT_NEAR(c.arcLength[i], 2.0 * i / 4.0, 1e-12);
    }
    for (size_t i = 4; i < 14; ++i) {
        EXPECT_NEAR(c.points[i].y, 5.0 * (i - 4) / 9.0, 1e-12);
        EXPECT_NEAR(c.radius[i], 2.0 * (0.2 + 0.2 * (i - 4) / 9.0), 1e-7);
    }
    // The given radius overrides the file's.
    const FramedCurve d = frameCurve(curve, 2.0, 0.3, 0.6, "x.txt", 0);
    for (double r : d.radius) EXPECT_EQ(r, 0.3);

    // A closed unit square: 4 x ceil(1 / 0.3) samples, the closing side included.
    const FramedCurve sq =
        frame(makeCurve({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, CurveBasis::Polyline, true),
              0.1, 0.3);
    EXPECT_EQ(sq.size(), 16u);
    EXPECT_NEAR(sq.length, 4.0, 1e-12);
    EXPECT_NEAR(sq.arcLength.back(), 3.75, 1e-12);
}

TEST(FrameCurve, ColoursAreLinearInTheSpanInSixteenthsAndExactAtThePoints) {
    // Scaled lengths 2 and 5 at step 0.6: 4 and 9 pieces (as above).
    Curve curve = makeCurve({{0, 0, 0}, {1, 0, 0}, {1, 2.5, 0}}, CurveBasis::Polyline);
    const Rgb a(1, 0, 0), b(0.2, 0.4, 1), c(0.2, 0.4, 1);
    curve.colours = {a, b, c};
    const FramedCurve f = frameCurve(curve, 2.0, 0.1, 0.6, "x.txt", 0);
    ASSERT_EQ(f.colours.size(), f.size());
    // Sample i of the first span is at u = i / 4: a multiple of 1/16, so exact.
    for (size_t i = 0; i <= 4; ++i) {
        const double u = i / 4.0;
        for (int ch = 0; ch < 3; ++ch)
            EXPECT_NEAR(f.colours[i][ch], (1 - u) * a[ch] + u * b[ch], 1e-15) << i;
    }
    EXPECT_EQ(f.colours[0], a);
    EXPECT_EQ(f.colours[4], b);
    // The second span has one colour: every sample exactly it.
    for (size_t i = 4; i < f.size(); ++i) EXPECT_EQ(f.colours[i], c) << i;

    // A long span of many samples: the colours step by 1/16 of the change,
    // each sample taking the nearest step to its own u.
    Curve ramp = makeCurve({{0, 0, 0}, {1, 0, 0}}, CurveBasis::Polyline);
    ramp.colours = {Rgb(0), Rgb(1, 0.5, 0.25)};
    const FramedCurve g = frameCurve(ramp, 1.0, 0.1, 1.0 / 64, "x.txt", 0);
    ASSERT_EQ(g.size(), 65u);
    std::vector<double> levels;
    for (size_t i = 0; i < g.size(); ++i) {
        const double u = i / 64.0, level = g.colours[i].r;
        EXPECT_LE(std::abs(level - u), 1.0 / 32 + 1e-12) << i;
        EXPECT_NEAR(level * 16, std::round(level * 16), 1e-12) << i;
        EXPECT_NEAR(g.colours[i].g, 0.5 * level, 1e-15);
        if (levels.empty() || levels.back() != level) levels.push_back(level);
    }
    EXPECT_EQ(levels.size(), 17u);  // 0, 1/16, ..., 1

    // Colours survive dropped coincident points and a closed curve; plies
    // take the yarn's colour sample by sample.
    Curve loop = makeCurve({{0, 0, 0}, {1, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 0}},
                           CurveBasis::Polyline, true);
    loop.colours = {Rgb(1, 0, 0), Rgb(0, 1, 0), Rgb(0.5), Rgb(0, 0, 1), Rgb(1, 1, 1)};
    const FramedCurve l = frameCurve(loop, 1.0, 0.2, 10.0, "x.txt", 0);
    ASSERT_EQ(l.size(), 3u);
    EXPECT_EQ(l.colours, (std::vector<Rgb>{Rgb(1, 0, 0), Rgb(0, 1, 0), Rgb(0, 0, 1)}));
    const std::vector<FramedCurve> plies = plyCurves(f, 3, 0.3);
    for (const FramedCurve& p : plies) EXPECT_EQ(p.colours, f.colours);
    const FramedCurve ring = frameCurve(
        [] {
            Curve r;
            for (int k = 0; k < 12; ++k)
                r.points.push_back({std::cos(kTwoPi * k / 12), std::sin(kTwoPi * k / 12), 0});
            for (int k = 0; k < 12; ++k) r.colours.push_back(Rgb(k / 11.0));
            r.closed = true;
            return r;
        }(),
        1.0, 0.1, 0.05, "ring.txt", 0);
    for (const FramedCurve& p : plyCurves(ring, 3, 0.7)) {
        ASSERT_EQ(p.colours.size(), p.size());
        for (size_t i = 0; i < p.size(); ++i)
            EXPECT_EQ(p.colours[i], ring.colours[i % ring.size()]);
    }
    // One colour per point or none.
    curve.colours.pop_back();
    expectInputError([&] { frameCurve(curve, 1.0, 0.1, 0.6, "x.txt", 4); },
                     {"x.txt: curve 4", "2 colours for 3 points"});
}

TEST(FrameCurve, NoSpacingExceedsMaxStep) {
    // A wild Catmull-Rom (overshooting spans) and a polyline, open and closed.
    const std::vector<Vec3> p = {{0, 0, 0}, {3, 0, 0}, {3.1, 0.1, 0}, {0, 2, 1}, {0.2, -1, 2}};
    for (CurveBasis basis : {CurveBasis::CatmullRom, CurveBasis::Polyline}) {
        for (bool closed : {false, true}) {
            for (double step : {0.5, 0.07}) {
                const FramedCurve c = frame(makeCurve(p, basis, closed), 0.1, step);
                const size_t segments = closed ? c.size() : c.size() - 1;
                for (size_t i = 0; i < segments; ++i)
                    EXPECT_LE(length(c.points[(i + 1) % c.size()] - c.points[i]), step);
                expectOrthonormalFrames(c);
            }
        }
    }
}

TEST(FrameCurve, CoincidentControlPointsAreDropped) {
    const std::vector<Vec3> p = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {2, 1, 0.5}};
    std::vector<Vec3> q = {p[0], p[0], p[1], p[2], p[2], p[2], p[3], p[3]};
    for (CurveBasis basis : {CurveBasis::CatmullRom, CurveBasis::Polyline}) {
        const FramedCurve a = frame(makeCurve(p, basis), 0.1, 0.1);
        const FramedCurve b = frame(makeCurve(q, basis), 0.1, 0.1);
        ASSERT_EQ(a.size(), b.size());
        for (size_t i = 0; i < a.size(); ++i) {
            EXPECT_EQ(a.points[i], b.points[i]);
            EXPECT_EQ(a.normals[i], b.normals[i]);
        }
    }
    // A closed curve that repeats its first point at the end.
    std::vector<Vec3> loop = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 0}};
    const FramedCurve c = frame(makeCurve(loop, CurveBasis::Polyline, true), 0.1, 10.0);
    EXPECT_EQ(c.size(), 3u);
    EXPECT_NEAR(c.length, 2.0 + std::sqrt(2.0), 1e-12);
}

// ---------------------------------------------------------------------------
// Rotation-minimising frame

TEST(FrameCurve, PlanarCurveKeepsItsNormalAtAFixedAngleToThePlane) {
    // An S curve in the plane z = 1: the RMF neither twists out of the plane
    // nor about T (dot(dN/ds, B) ~ 0).
    for (CurveBasis basis : {CurveBasis::CatmullRom, CurveBasis::Polyline}) {
        // Starting along +x, the first normal is -z (coordinateSystem): it
        // must stay perpendicular to the plane.
        const FramedCurve c = frame(
            makeCurve({{0, 0, 1}, {1, 0, 1}, {2, 1, 1}, {3, -1, 1}, {4, 0, 1}, {4, 2, 1}}, basis),
            0.1, 0.01);
        expectOrthonormalFrames(c);
        EXPECT_EQ(c.normals[0], Vec3(0, 0, -1));
        for (size_t i = 0; i < c.size(); ++i) {
            EXPECT_NEAR(c.normals[i].z, -1.0, 1e-12) << i;
            EXPECT_NEAR(c.tangents[i].z, 0.0, 1e-12) << i;
        }
        EXPECT_LT(maxAbs(twistRates(c)), 1e-9);
        EXPECT_EQ(c.holonomy, 0.0);
    }
    // A tilted start: the normal keeps its (non-trivial) angle to the plane.
    const FramedCurve c =
        frame(makeCurve({{0, 0, 1}, {1, 1, 1}, {2, 0, 1}, {3, -1, 1}, {4, 0, 1}, {4, 2, 1}},
                        CurveBasis::CatmullRom),
              0.1, 0.01);
    const double z0 = c.normals[0].z;
    EXPECT_GT(std::abs(z0), 0.1);
    EXPECT_LT(std::abs(z0), 0.9);
    for (size_t i = 0; i < c.size(); ++i) EXPECT_NEAR(c.normals[i].z, z0, 1e-12) << i;
    EXPECT_LT(maxAbs(twistRates(c)), 1e-4);
}

TEST(FrameCurve, HelixFrameTurnsAgainstTheFrenetFrameAtTheTorsion) {
    // Helix (a cos t, a sin t, b t): curvature a / c^2, torsion tau = b / c^2,
    // speed c. An RMF normal at angle theta from the Frenet normal obeys
    // theta' = -tau (Bishop 1975), so theta(s) = theta(0) - tau s.
    const double a = 1.0, b = 0.3, c2 = a * a + b * b, speed = std::sqrt(c2), tau = b / c2;
    const int count = 3000;
    const double t1 = 4.0 * kPi;
    const auto helix = [&](double t) { return Vec3(a * std::cos(t), a * std::sin(t), b * t); };
    const FramedCurve c =
        frame(makeCurve(sampled(helix, 0.0, t1, count), CurveBasis::Polyline), 0.1, 10.0);
    ASSERT_EQ(c.size(), static_cast<size_t>(count));
    expectOrthonormalFrames(c);
    double theta0 = 0;
    double worst = 0;
    for (int i = 0; i < count; ++i) {
        const double t = t1 * i / (count - 1);
        const Vec3 T = Vec3(-a * std::sin(t), a * std::cos(t), b) / speed;
        const Vec3 n(-std::cos(t), -std::sin(t), 0);
        const double theta = std::atan2(dot(c.normals[i], cross(T, n)), dot(c.normals[i], n));
        if (i == 0) theta0 = theta;
        worst = std::max(worst, std::abs(wrapAngle(theta - theta0 + tau * speed * t)));
    }
    EXPECT_LT(worst, 1e-4);
    EXPECT_LT(maxAbs(twistRates(c)), 1e-5);
}

// The RMF normal carried across one segment by double reflection (Wang et al.
// 2008), written out again for the seam test.
Vec3 carryNormal(const Vec3& x0, const Vec3& t0, const Vec3& r0, const Vec3& x1, const Vec3& t1) {
    const Vec3 v1 = x1 - x0;
    const Vec3 rL = r0 - (2.0 / dot(v1, v1)) * dot(v1, r0) * v1;
    const Vec3 tL = t0 - (2.0 / dot(v1, v1)) * dot(v1, t0) * v1;
    const Vec3 v2 = t1 - tL;
    return rL - (2.0 / dot(v2, v2)) * dot(v2, rL) * v2;
}

// Across the closing segment the frame must continue into the first one,
// turned only by that segment's share -holonomy h / L of the correction.
void expectSeamless(const FramedCurve& c, double tol) {
    const size_t n = c.size();
    const double h = length(c.points[0] - c.points[n - 1]);
    const Vec3 carried = carryNormal(c.points[n - 1], c.tangents[n - 1], c.normals[n - 1],
                                     c.points[0], c.tangents[0]);
    const double a = -c.holonomy * h / c.length;
    const Vec3 expected = std::cos(a) * carried + std::sin(a) * cross(c.tangents[0], carried);
    EXPECT_LT(length(expected - c.normals[0]), tol);
}

TEST(FrameCurve, ClosedCircleHasNoHolonomy) {
    const auto circle = [](double t) { return Vec3(2 * std::cos(t), 2 * std::sin(t), 0.5); };
    for (CurveBasis basis : {CurveBasis::Polyline, CurveBasis::CatmullRom}) {
        const FramedCurve c =
            frame(makeCurve(sampled(circle, 0.0, kTwoPi, 24, true), basis, true), 0.1, 0.05);
        EXPECT_NEAR(c.holonomy, 0.0, 1e-9);
        expectOrthonormalFrames(c);
        expectSeamless(c, 1e-9);
        EXPECT_LT(maxAbs(twistRates(c)), 1e-6);
    }
}

// A (2,3) torus knot ((A + B cos 3t) cos 2t, (A + B cos 3t) sin 2t, B sin 3t)
// and its first three derivatives in t.
struct TorusKnot {
    double A = 2, B = 1;

    void eval(double t, Vec3 d[4]) const {
        const double rho = A + B * std::cos(3 * t), r1 = -3 * B * std::sin(3 * t),
                     r2 = -9 * B * std::cos(3 * t), r3 = 27 * B * std::sin(3 * t);
        const Vec3 e(std::cos(2 * t), std::sin(2 * t), 0), f(-std::sin(2 * t), std::cos(2 * t), 0);
        // (x, y) = rho e with e' = 2 f, f' = -2 e.
        d[0] = rho * e + Vec3(0, 0, B * std::sin(3 * t));
        d[1] = r1 * e + 2 * rho * f + Vec3(0, 0, 3 * B * std::cos(3 * t));
        d[2] = (r2 - 4 * rho) * e + 4 * r1 * f + Vec3(0, 0, -9 * B * std::sin(3 * t));
        d[3] = (r3 - 12 * r1) * e + (6 * r2 - 8 * rho) * f + Vec3(0, 0, -27 * B * std::cos(3 * t));
    }
    Vec3 point(double t) const {
        Vec3 d[4];
        eval(t, d);
        return d[0];
    }
    // Total torsion: integral of tau |r'| dt, tau = (r' x r'') . r''' / |r' x r''|^2.
    double totalTorsion() const {
        const auto integrand = [&](double t) {
            Vec3 d[4];
            eval(t, d);
            const Vec3 c = cross(d[1], d[2]);
            return dot(c, d[3]) / dot(c, c) * length(d[1]);
        };
        return weft::testing::simpson(integrand, 0.0, kTwoPi, 20000);
    }
};

TEST(FrameCurve, ClosedTorusKnotFrameIsSeamless) {
    // The RMF comes back turned by minus the total torsion (mod 2 pi); the
    // correction spreads that uniformly, so the angular velocity about T is
    // -holonomy / L on every segment, the closing one included.
    const TorusKnot knot;
    const auto f = [&](double t) { return knot.point(t); };
    for (CurveBasis basis : {CurveBasis::Polyline, CurveBasis::CatmullRom}) {
        const int count = basis == CurveBasis::Polyline ? 4000 : 300;
        const FramedCurve c = frame(makeCurve(sampled(f, 0.0, kTwoPi, count, true), basis, true),
                                    0.1, basis == CurveBasis::Polyline ? 1.0 : 0.01);
        expectOrthonormalFrames(c);
        EXPECT_NEAR(wrapAngle(c.holonomy + knot.totalTorsion()), 0.0, 1e-4);
        EXPECT_GT(std::abs(c.holonomy), 0.1);  // a non-trivial case
        const std::vector<double> w = twistRates(c);
        const double expected = -c.holonomy / c.length;
        double worst = 0;
        for (double x : w) worst = std::max(worst, std::abs(x - expected));
        EXPECT_LT(worst, 5e-5);  // measured 4e-6 (polyline), 1e-5 (Catmull-Rom)
        expectSeamless(c, 1e-6);
    }
}

// ---------------------------------------------------------------------------
// Plies

TEST(PlyRadius, PliesTouchEachOtherAndTheYarnSurface) {
    EXPECT_EQ(plyRadius(2.0, 1), 2.0);
    EXPECT_NEAR(plyRadius(2.0, 2), 1.0, 1e-15);
    for (int k = 2; k <= 16; ++k) {
        const double r = plyRadius(1.0, k);
        EXPECT_NEAR((1.0 - r) * std::sin(kPi / k), r, 1e-15) << k;
    }
    expectInputError([] { plyRadius(1.0, 0); }, {"plies", ">= 1"});
    expectInputError([] { plyRadius(0.0, 3); }, {"radius"});
    expectInputError([] { plyRadius(std::nan(""), 3); }, {"radius"});
}

FramedCurve wavyYarn(double maxStep) {
    Curve c = makeCurve({{0, 0, 0}, {1, 0.5, 0.2}, {2, -0.4, 0.6}, {3, 0.3, 0.1}, {4, 0, 0}},
                        CurveBasis::CatmullRom);
    c.radii = {0.2f, 0.25f, 0.3f, 0.2f, 0.15f};
    return frameCurve(c, 1.0, std::nullopt, maxStep, "wavy.bcc", 0);
}

TEST(PlyCurves, PliesTouchAndSitAtTheirOffset) {
    const FramedCurve yarn = wavyYarn(0.01);
    for (int k : {2, 3, 5}) {
        const std::vector<FramedCurve> plies = plyCurves(yarn, k, 0.4);
        ASSERT_EQ(plies.size(), static_cast<size_t>(k));
        for (const FramedCurve& p : plies) {
            ASSERT_EQ(p.size(), yarn.size());
            EXPECT_FALSE(p.closed);
            expectOrthonormalFrames(p);
        }
        for (size_t i = 0; i < yarn.size(); ++i) {
            const double rPly = plyRadius(yarn.radius[i], k);
            double closest = std::numeric_limits<double>::infinity();
            for (int j = 0; j < k; ++j) {
                const Vec3 d = plies[j].points[i] - yarn.points[i];
                EXPECT_NEAR(length(d), yarn.radius[i] - rPly, 1e-12);
                EXPECT_NEAR(dot(d, yarn.tangents[i]), 0.0, 1e-12);
                EXPECT_NEAR(plies[j].radius[i], rPly, 1e-15);
                for (int l = j + 1; l < k; ++l)
                    closest = std::min(closest, length(plies[l].points[i] - plies[j].points[i]));
            }
            EXPECT_NEAR(closest, 2.0 * rPly, 1e-12) << "k " << k << " sample " << i;
        }
    }
}

TEST(PlyCurves, OnePlyIsTheYarn) {
    const FramedCurve yarn = wavyYarn(0.02);
    const std::vector<FramedCurve> plies = plyCurves(yarn, 1, 0.7);
    ASSERT_EQ(plies.size(), 1u);
    EXPECT_EQ(plies[0].points, yarn.points);
    EXPECT_EQ(plies[0].radius, yarn.radius);
    EXPECT_EQ(plies[0].normals, yarn.normals);
}

TEST(PlyCurves, PositiveTwistIsRightHandedWithPeriodTwoROverTwist) {
    // A straight yarn along +z: N = +x, B = +y, so ply j must be the helix of
    // PlyGeometry::fiberCentre (counter-clockwise seen from +z) at radius
    // R - R_ply, rate pi ply_twist / R, period 2 R / ply_twist.
    const double R = 0.5, twist = 0.7, period = 2 * R / twist, L = 2 * period;
    const FramedCurve yarn =
        frame(makeCurve({{0, 0, 0}, {0, 0, L}}, CurveBasis::Polyline), R, L / 64 * (1 + 1e-9));
    ASSERT_EQ(yarn.size(), 65u);
    EXPECT_EQ(yarn.normals[10], Vec3(1, 0, 0));
    EXPECT_EQ(yarn.binormals[10], Vec3(0, 1, 0));
    const int k = 3;
    const double offset = R - plyRadius(R, k);
    const std::vector<FramedCurve> plies = plyCurves(yarn, k, twist);
    for (int j = 0; j < k; ++j) {
        PlyGeometry helix;
        helix.params.twist = twist;
        helix.radius = R;
        const double a0 = kTwoPi * j / k;
        helix.centres = {{offset * std::cos(a0), offset * std::sin(a0)}};
        for (size_t i = 0; i < yarn.size(); ++i) {
            const double z = yarn.points[i].z;
            EXPECT_LT(length(plies[j].points[i] - helix.fiberCentre(0, z)), 1e-12);
            if (i + 1 < yarn.size()) {
                const Vec3 a = plies[j].points[i], b = plies[j].points[i + 1];
                EXPECT_GT(a.x * b.y - a.y * b.x, 0.0);  // counter-clockwise from +z
            }
        }
        // One period later (sample 32 is z = period) the ply is back above its start.
        EXPECT_NEAR(yarn.points[32].z, period, 1e-12);
        EXPECT_LT(length(plies[j].points[32] - plies[j].points[0] - Vec3(0, 0, period)), 1e-12);
    }
    // Negative twist: left-handed (clockwise from +z).
    const std::vector<FramedCurve> left = plyCurves(yarn, k, -twist);
    const Vec3 a = left[0].points[1], b = left[0].points[2];
    EXPECT_LT(a.x * b.y - a.y * b.x, 0.0);
}

FramedCurve ringYarn(double ringRadius, double yarnRadius) {
    const auto f = [&](double t) {
        return Vec3(ringRadius * std::cos(t), ringRadius * std::sin(t), 0.0);
    };
    return frame(makeCurve(sampled(f, 0.0, kTwoPi, 400, true), CurveBasis::Polyline, true),
                 yarnRadius, 10.0);
}

// The closing segment of a closed curve is about as long as its neighbours
// (no jump), and every segment is short.
void expectNoSeam(const FramedCurve& c, double maxSegment) {
    const size_t n = c.size();
    const double closing = length(c.points[0] - c.points[n - 1]);
    const double before = length(c.points[n - 1] - c.points[n - 2]);
    EXPECT_LT(closing, 1.5 * before);
    EXPECT_GT(closing, before / 1.5);
    for (size_t i = 0; i + 1 < n; ++i) EXPECT_LT(length(c.points[i + 1] - c.points[i]), maxSegment);
}

TEST(PlyCurves, ClosedYarnRoundsTheTwistAndJoinsThePlies) {
    const double R = 1.0;
    const FramedCurve yarn = ringYarn(10.0, R);
    ASSERT_TRUE(yarn.closed);
    struct Case {
        int k;
        double turns;  // loop turn / (2 pi / k) before rounding
        size_t curves;
    };
    // m = round(turns) (at least +-1 for a non-zero twist); gcd(|m|, k) curves.
    for (const Case& cs : {Case{3, 1.3, 1}, Case{3, 2.8, 3}, Case{3, 1.9, 1}, Case{4, 2.2, 2},
                           Case{4, -1.2, 1}, Case{3, 0.0, 3}, Case{3, 0.01, 1}, Case{2, 4.4, 2}}) {
        // loop turn = pi twist L / R.
        const double twist = cs.turns * (kTwoPi / cs.k) * R / (kPi * yarn.length);
        const std::vector<FramedCurve> plies = plyCurves(yarn, cs.k, twist);
        ASSERT_EQ(plies.size(), cs.curves) << cs.k << " " << cs.turns;
        const double rPly = plyRadius(R, cs.k);
        size_t total = 0;
        for (const FramedCurve& p : plies) {
            EXPECT_TRUE(p.closed);
            EXPECT_EQ(p.size() % yarn.size(), 0u);
            total += p.size();
            for (size_t i = 0; i < p.size(); ++i) {
                const size_t y = i % yarn.size();
                EXPECT_NEAR(length(p.points[i] - yarn.points[y]), R - rPly, 1e-12);
            }
            expectNoSeam(p, 0.5);
            expectOrthonormalFrames(p);
            expectSeamless(p, 1e-6);
        }
        EXPECT_EQ(total, cs.k * yarn.size());
    }
}

// ---------------------------------------------------------------------------
// Tubes and fibers

TEST(ToTube, CopiesPointsAndRadii) {
    const FramedCurve yarn = wavyYarn(0.05);
    const Tube t = toTube(yarn);
    EXPECT_EQ(t.points, yarn.points);
    ASSERT_EQ(t.radii.size(), yarn.size());
    for (size_t i = 0; i < yarn.size(); ++i)
        EXPECT_EQ(t.radii[i], static_cast<float>(yarn.radius[i]));
    EXPECT_FALSE(t.closed);
    EXPECT_EQ(t.segmentCount(), yarn.size() - 1);
    const Tube ring = toTube(ringYarn(3.0, 0.2));
    EXPECT_TRUE(ring.closed);
    EXPECT_EQ(ring.segmentCount(), ring.points.size());
}

PlyParams fiberParams(double twist) {
    PlyParams p;
    p.fibers = 60;
    p.density = 0.4;
    p.twist = twist;
    return p;
}

TEST(FiberTubes, StraightPlyMatchesFiberCentres) {
    // Independent construction: a straight ply along +z is the generator's
    // own ply, so every fiber point is PlyGeometry::fiberCentre(i, z).
    const double R = 0.5, L = 3.0;
    const PlyParams params = fiberParams(0.3);
    const FramedCurve ply = frame(makeCurve({{0, 0, 0}, {0, 0, L}}, CurveBasis::Polyline), R, 0.02);
    const std::vector<Tube> fibers = fiberTubes(ply, params, 7);
    const PlyGeometry g = generatePly(params, R, 1.0, 7);
    ASSERT_EQ(fibers.size(), 60u);
    for (size_t f = 0; f < fibers.size(); ++f) {
        ASSERT_EQ(fibers[f].points.size(), ply.size());
        EXPECT_FALSE(fibers[f].closed);
        for (size_t i = 0; i < ply.size(); ++i) {
            const Vec3 expected = g.fiberCentre(static_cast<int>(f), ply.points[i].z);
            EXPECT_LT(length(fibers[f].points[i] - expected), 1e-12) << f << " " << i;
            EXPECT_EQ(fibers[f].radii[i], static_cast<float>(g.fiberRadius));
        }
    }
    EXPECT_NEAR(g.fiberRadius, R * std::sqrt(0.4 / 60), 1e-15);
}

TEST(FiberTubes, FibersStayInsideACurvedPly) {
    const FramedCurve yarn = wavyYarn(0.01);
    const std::vector<FramedCurve> plies = plyCurves(yarn, 3, 0.5);
    const PlyParams params = fiberParams(0.4);
    for (const FramedCurve& ply : plies) {
        const std::vector<Tube> fibers = fiberTubes(ply, params, 3);
        ASSERT_EQ(fibers.size(), 60u);
        for (const Tube& fiber : fibers) {
            for (size_t i = 0; i < ply.size(); ++i) {
                const Vec3 d = fiber.points[i] - ply.points[i];
                const double r = ply.radius[i] * std::sqrt(0.4 / 60);
                EXPECT_NEAR(fiber.radii[i], r, 1e-6 * r);
                EXPECT_LE(length(d) + r, ply.radius[i] * (1 + 1e-9));
                EXPECT_NEAR(dot(d, ply.tangents[i]), 0.0, 1e-12);
            }
        }
    }
}

TEST(FiberTubes, VaryingRadiusScalesAndTurnsByTheIntegral) {
    // A straight ply along +z whose radius grows linearly from R0 to R1: the
    // cross-section is scaled by R(z) / R0 and turned by
    // integral pi alpha / R = pi alpha L / (R1 - R0) ln(R(z) / R0).
    const double R0 = 0.2, R1 = 0.5, L = 4.0, alpha = 0.6;
    Curve c = makeCurve({{0, 0, 0}, {0, 0, L}}, CurveBasis::Polyline);
    c.radii = {static_cast<float>(R0), static_cast<float>(R1)};
    const FramedCurve ply = frameCurve(c, 1.0, std::nullopt, 0.002, "cone.txt", 4);
    const PlyParams params = fiberParams(alpha);
    const std::vector<Tube> fibers = fiberTubes(ply, params, 11);
    const PlyGeometry g = generatePly(params, ply.radius[0], 1.0, 11);
    const double r0 = ply.radius[0], r1 = ply.radius.back();
    for (size_t f = 0; f < fibers.size(); f += 7) {
        for (size_t i = 0; i < ply.size(); i += 13) {
            const double z = ply.points[i].z, R = r0 + (r1 - r0) * z / L;
            const double psi = kPi * alpha * L / (r1 - r0) * std::log(R / r0);
            const double cx = g.centres[f][0], cy = g.centres[f][1], s = R / r0;
            const Vec3 expected(s * (std::cos(psi) * cx - std::sin(psi) * cy),
                                s * (std::sin(psi) * cx + std::cos(psi) * cy), z);
            EXPECT_LT(length(fibers[f].points[i] - expected), 1e-6 * R) << f << " " << i;
            EXPECT_NEAR(fibers[f].radii[i], g.fiberRadius * s, 1e-6 * g.fiberRadius * s);
        }
    }
}

// The turn of fiber f at each sample, from its local coordinates in (N, B).
std::vector<double> fiberTurns(const FramedCurve& ply, const Tube& fiber,
                               const std::array<double, 2>& centre) {
    std::vector<double> turns;
    const double a0 = std::atan2(centre[1], centre[0]);
    for (size_t i = 0; i < ply.size(); ++i) {
        const Vec3 d = fiber.points[i] - ply.points[i];
        turns.push_back(
            wrapAngle(std::atan2(dot(d, ply.binormals[i]), dot(d, ply.normals[i])) - a0));
    }
    return turns;
}

TEST(FiberTubes, ClosedPlyMakesWholeTurns) {
    const double R = 0.3;
    const FramedCurve ring = ringYarn(2.0, R);  // one ply (k = 1) is the ring
    const PlyParams params0 = fiberParams(0.0);
    const PlyGeometry g = generatePly(params0, R, 1.0, 5);
    size_t f = 0;  // a fiber off the axis
    while (std::hypot(g.centres[f][0], g.centres[f][1]) < 0.3 * R) ++f;
    // loop turn pi alpha L / R: 2.3 turns rounds to 2, 0.2 to 1 (never 0), 0 stays 0.
    for (auto [turns, whole] : {std::pair{2.3, 2.0}, std::pair{0.2, 1.0}, std::pair{0.0, 0.0}}) {
        PlyParams params = params0;
        params.twist = turns * kTwoPi * R / (kPi * ring.length);
        const std::vector<Tube> fibers = fiberTubes(ring, params, 5);
        ASSERT_TRUE(fibers[f].closed);
        const std::vector<double> got = fiberTurns(ring, fibers[f], g.centres[f]);
        for (size_t i = 0; i < ring.size(); ++i) {
            const double expected = kTwoPi * whole * ring.arcLength[i] / ring.length;
            EXPECT_NEAR(wrapAngle(got[i] - expected), 0.0, 1e-9) << turns << " " << i;
        }
        for (const Tube& fiber : fibers) {
            FramedCurve asCurve;
            asCurve.points = fiber.points;
            expectNoSeam(asCurve, 0.1);
        }
    }
}

// ---------------------------------------------------------------------------
// Sample spacing

TEST(SampleStep, SimpleValues) {
    EXPECT_DOUBLE_EQ(sampleStep(1.0, 1, 0.0, nullptr), 0.25);
    EXPECT_DOUBLE_EQ(sampleStep(2.0, 3, 0.0, nullptr), 0.5);
    // P_ply = 2 R / |twist| = 4: 4 / 32.
    EXPECT_DOUBLE_EQ(sampleStep(1.0, 1, 0.5, nullptr), 0.125);
    EXPECT_DOUBLE_EQ(sampleStep(1.0, 1, -0.5, nullptr), 0.125);
    EXPECT_DOUBLE_EQ(sampleStep(1.0, 3, 0.5, nullptr, 16), 0.25);
    PlyParams fibers = fiberParams(0.5);
    // k = 1: R_ply = R, stretch 1, P_fiber = 2 / 0.5 = 4: 4 / 32.
    EXPECT_DOUBLE_EQ(sampleStep(1.0, 1, 0.0, &fibers), 0.125);
    fibers.twist = 1.0;
    // k = 2: R_ply = 0.5, P_ply = 2, P_fiber = 1, stretch sqrt(1 + (pi 0.5)^2).
    const double stretch = std::sqrt(1.0 + sqr(kPi * 0.5));
    EXPECT_DOUBLE_EQ(sampleStep(1.0, 2, 1.0, &fibers, 16), 1.0 / (16 * stretch));
    fibers.twist = 0.0;  // straight fibers add no limit
    EXPECT_DOUBLE_EQ(sampleStep(1.0, 2, 1.0, &fibers, 16), 2.0 / 16);
    expectInputError([] { sampleStep(0.0, 1, 0.0, nullptr); }, {"radius"});
    expectInputError([] { sampleStep(1.0, 0, 0.0, nullptr); }, {"plies"});
    expectInputError([] { sampleStep(1.0, 2, std::nan(""), nullptr); }, {"ply_twist"});
    PlyParams bad = fiberParams(0.3);
    bad.density = 1.5;
    expectInputError([&] { sampleStep(1.0, 2, 0.3, &bad); }, {"density"});
}

// ---------------------------------------------------------------------------
// Input errors

TEST(FrameCurve, InputErrorsNameTheSourceAndCurve) {
    const Curve same = makeCurve({{1, 2, 3}, {1, 2, 3}, {1, 2, 3}}, CurveBasis::CatmullRom);
    expectInputError([&] { frameCurve(same, 1.0, 0.1, 0.1, "knit.bcc", 3); },
                     {"knit.bcc", "curve 3", "distinct"});
    const Curve line = makeCurve({{0, 0, 0}, {1, 0, 0}}, CurveBasis::Polyline);
    const double nan = std::nan(""), inf = std::numeric_limits<double>::infinity();
    for (double s : {nan, inf, 0.0, -1.0})
        expectInputError([&] { frameCurve(line, s, 0.1, 0.1, "a.txt", 5); },
                         {"a.txt", "curve 5", "scale"});
    for (double r : {nan, inf, 0.0, -0.1})
        expectInputError([&] { frameCurve(line, 1.0, r, 0.1, "a.txt", 6); },
                         {"a.txt", "curve 6", "radius"});
    expectInputError([&] { frameCurve(line, 1.0, std::nullopt, 0.1, "b.obj", 2); },
                     {"b.obj", "curve 2", "radii", "radius"});
    const Curve far = makeCurve({{0, 0, 0}, {1e10, 0, 0}}, CurveBasis::Polyline);
    expectInputError([&] { frameCurve(far, 1e300, 0.1, 0.1, "c.txt", 1); },
                     {"c.txt", "curve 1", "not finite"});
    Curve badRadius = line;
    badRadius.radii = {0.1f, 0.0f};
    expectInputError([&] { frameCurve(badRadius, 1.0, std::nullopt, 0.1, "c.txt", 1); },
                     {"c.txt", "curve 1", "radius of point 1"});
    const Curve closedPair = makeCurve({{0, 0, 0}, {1, 0, 0}}, CurveBasis::Polyline, true);
    expectInputError([&] { frameCurve(closedPair, 1.0, 0.1, 0.1, "d.bcc", 0); },
                     {"d.bcc", "curve 0", "closed", "3 distinct"});
    const Curve huge = makeCurve({{0, 0, 0}, {1e9, 0, 0}}, CurveBasis::Polyline);
    expectInputError([&] { frameCurve(huge, 1.0, 0.1, 1e-3, "e.bcc", 9); },
                     {"e.bcc", "curve 9", "samples"});
    EXPECT_THROW(frameCurve(line, 1.0, 0.1, 0.0, "f.bcc", 0), std::invalid_argument);
    const FramedCurve yarn = frame(line, 0.1, 0.1);
    expectInputError([&] { plyCurves(yarn, 3, nan); }, {"ply_twist"});
    expectInputError([&] { plyCurves(yarn, 0, 0.1); }, {"plies"});
}

}  // namespace
}  // namespace weft::render
