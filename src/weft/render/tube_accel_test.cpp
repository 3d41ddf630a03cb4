#include "weft/render/tube_accel.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "weft/core/math.h"
#include "weft/core/rng.h"

namespace weft::render {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// A straight tube along +x through (0, 0, z) of the given radius, split into segments.
Tube straightTube(double z, double radius, int segments = 8, double halfLength = 4.0) {
    Tube tube;
    for (int i = 0; i <= segments; ++i) {
        tube.points.push_back({-halfLength + 2.0 * halfLength * i / segments, 0.0, z});
        tube.radii.push_back(static_cast<float>(radius));
    }
    return tube;
}

// A closed circular tube of centre-line radius `ring` in the x-y plane.
Tube ringTube(double ring, double radius, int points) {
    Tube tube;
    tube.closed = true;
    for (int i = 0; i < points; ++i) {
        const double a = kTwoPi * i / points;
        tube.points.push_back({ring * std::cos(a), ring * std::sin(a), 0.0});
        tube.radii.push_back(static_cast<float>(radius));
    }
    return tube;
}

TEST(TubeAccel, HitPointTangentAndNormalOfAStraightTube) {
    TubeAccel accel;
    accel.addGeometry({straightTube(0.0, 0.5)}, 7);
    accel.commit();
    TubeHit hit;
    ASSERT_TRUE(accel.intersect({0.3, 0.0, 5.0}, {0, 0, -1}, kInf, {}, &hit));
    EXPECT_NEAR(hit.t, 4.5, 1e-5);
    EXPECT_NEAR(std::abs(hit.tangent.x), 1.0, 1e-6);
    EXPECT_NEAR(hit.normal.z, 1.0, 1e-5);
    EXPECT_EQ(hit.material, 7);
    EXPECT_EQ(hit.id.geometry, 0u);
    EXPECT_EQ(hit.id.tube, 0u);
    // Oblique hit: the normal points from the axis to the hit point.
    ASSERT_TRUE(accel.intersect({0.0, 5.0, 0.3}, {0, -1, 0}, kInf, {}, &hit));
    EXPECT_NEAR(hit.point.y, std::sqrt(0.25 - 0.09), 1e-5);
    EXPECT_NEAR(hit.normal.y, std::sqrt(0.25 - 0.09) / 0.5, 1e-5);
    EXPECT_NEAR(hit.normal.z, 0.3 / 0.5, 1e-5);
    EXPECT_NEAR(dot(hit.normal, hit.tangent), 0.0, 1e-9);
    // tMax is respected.
    EXPECT_FALSE(accel.intersect({0.3, 0.0, 5.0}, {0, 0, -1}, 4.0, {}, &hit));
    EXPECT_TRUE(accel.occluded({0.3, 0.0, 5.0}, {0, 0, -1}, 5.0, {}));
    EXPECT_FALSE(accel.occluded({0.3, 0.0, 5.0}, {0, 0, -1}, 4.0, {}));
}

TEST(TubeAccel, MaterialsAlongTheTubesFollowTheSegmentIndex) {
    // Two parallel tubes of 8 segments each (x in [-4, 4], 1 per segment) in
    // one geometry; segment k of both has material 10 + k; a third tube of
    // one material in another geometry.
    TubeAccel accel;
    std::vector<int> along;
    for (int k = 0; k < 8; ++k) along.push_back(10 + k);
    accel.addGeometry({straightTube(0.0, 0.3), straightTube(-2.0, 0.3)}, 3, along);
    Tube third = straightTube(0.0, 0.3);
    for (Vec3& p : third.points) p.y = 5;
    accel.addGeometry({third}, 4);
    accel.commit();
    for (int k = 0; k < 8; ++k) {
        const double x = -4.0 + k + 0.5;
        TubeHit hit;
        ASSERT_TRUE(accel.intersect({x, 0.0, 5.0}, {0, 0, -1}, kInf, {}, &hit));
        EXPECT_EQ(hit.material, 10 + k) << x;
        EXPECT_EQ(hit.id.tube, 0u);
        // From below: the second tube of the geometry, the same segment index.
        ASSERT_TRUE(accel.intersect({x, 0.0, -5.0}, {0, 0, 1}, kInf, {}, &hit));
        EXPECT_EQ(hit.id.tube, 1u);
        EXPECT_EQ(hit.material, 10 + k) << x;
        ASSERT_TRUE(accel.intersect({x, 5.0, 5.0}, {0, 0, -1}, kInf, {}, &hit));
        EXPECT_EQ(hit.material, 4);
    }
    // One material per segment of every tube, or none.
    TubeAccel bad;
    EXPECT_THROW(bad.addGeometry({straightTube(0.0, 0.3, 8), straightTube(1.0, 0.3, 7)}, 0, along),
                 std::logic_error);
}

TEST(TubeAccel, RaysLeavingATubeIgnoreItsInteriorButSeeOtherTubes) {
    TubeAccel accel;
    accel.addGeometry({straightTube(0.0, 0.5)}, 0);
    accel.addGeometry({straightTube(-2.0, 0.5)}, 1);
    accel.commit();
    TubeHit hit;
    ASSERT_TRUE(accel.intersect({0.1, 0.0, 5.0}, {0, 0, -1}, kInf, {}, &hit));
    const TubeId top = hit.id;
    // Transmitted straight on (the T lobe): passes through its own tube, hits the one below.
    ASSERT_TRUE(accel.intersect(hit.point, {0, 0, -1}, kInf, top, &hit));
    EXPECT_EQ(hit.id.geometry, 1u);
    EXPECT_NEAR(hit.point.z, -1.5, 1e-5);
    // Without the origin tube the ray stops at its own surface.
    TubeHit self;
    ASSERT_TRUE(accel.intersect({0.1, 0.0, 0.5}, {0, 0, -1}, kInf, {}, &self));
    EXPECT_EQ(self.id.geometry, 0u);
    // Reflected away from the tube: nothing to hit.
    EXPECT_FALSE(accel.intersect({0.1, 0.0, 0.5}, {0, 0.6, 0.8}, kInf, top, &hit));
    EXPECT_FALSE(accel.occluded({0.1, 0.0, 0.5}, {0, 0.6, 0.8}, kInf, top));
    // Oblique transmission at a grazing angle to the axis, across several
    // segments of the tube: no hit on the tube's own joints.
    const Vec3 start{-3.0, 0.0, 0.5};
    const Vec3 dir = normalize(Vec3{1.0, 0.0, -0.4});
    ASSERT_TRUE(accel.intersect(start, dir, kInf, top, &hit));
    EXPECT_EQ(hit.id.geometry, 1u);
    // Shadow rays use the same rule.
    EXPECT_TRUE(accel.occluded({0.1, 0.0, 0.5}, {0, 0, -1}, kInf, top));
    EXPECT_FALSE(accel.occluded({0.1, 0.0, 0.5}, {0, 0, -1}, 1.0, top));
}

TEST(TubeAccel, TransmittedRaysCrossTubesAtRandomPointsAndAngles) {
    // Every ray that enters the ring tube from outside and continues straight
    // on must leave it without another hit on the same tube near the entry
    // (joints of the closed ring included), and may only hit it again on the
    // far side of the ring. Segments longer and much shorter than the radius
    // (Embree's joint spheres then reach past the next segment).
    for (const int points : {24, 192}) {
        TubeAccel accel;
        const double ring = 3.0, radius = 0.4;
        accel.addGeometry({ringTube(ring, radius, points)}, 0);
        accel.commit();
        Rng rng(1, 2);
        int crossings = 0;
        for (int i = 0; i < 4000; ++i) {
            // Aim at a random point of the ring's centre line from a random direction.
            const double a = kTwoPi * rng.uniform();
            const Vec3 target{ring * std::cos(a), ring * std::sin(a), 0.0};
            const double z = 2 * rng.uniform() - 1, phi = kTwoPi * rng.uniform();
            const Vec3 dir{std::sqrt(1 - z * z) * std::cos(phi),
                           std::sqrt(1 - z * z) * std::sin(phi), z};
            TubeHit entry;
            if (!accel.intersect(target - dir * 10.0, dir, kInf, {}, &entry)) continue;
            ASSERT_LT(dot(dir, entry.normal), 0.0);
            TubeHit next;
            if (accel.intersect(entry.point, dir, kInf, entry.id, &next)) {
                // A second hit must be a new entry from outside, far from the first.
                EXPECT_LT(dot(dir, next.normal), 0.0);
                EXPECT_GT(length(next.point - entry.point), 2 * radius)
                    << "ray " << i << ", " << points << " points";
            }
            ++crossings;
        }
        EXPECT_GT(crossings, 3000);
    }
}

TEST(TubeAccel, AClosedLoopIsHitAgainFromAcrossTheLoop) {
    TubeAccel accel;
    accel.addGeometry({ringTube(3.0, 0.4, 32)}, 0);
    accel.commit();
    TubeHit hit;
    // From the loop's centre to its inner surface, between two joints (a ray
    // through a joint vertex exactly is an Embree edge case of measure zero).
    const Vec3 dir{std::cos(0.05), std::sin(0.05), 0.0};
    ASSERT_TRUE(accel.intersect({0.0, 0.0, 0.0}, dir, kInf, {}, &hit));
    ASSERT_NEAR(hit.t, 2.6, 0.02);
    const TubeId ring = hit.id;
    // Reflected back across the loop: the far side of the same tube is a real hit.
    TubeHit across;
    ASSERT_TRUE(accel.intersect(hit.point, -dir, kInf, ring, &across));
    EXPECT_NEAR(across.t, 5.2, 0.04);
    EXPECT_LT(dot(-dir, across.normal), 0.0);
}

// The shading tangent is the sampled curve's, not the segment's: on a ring of
// 12 segments (30 degrees each, so a segment's own direction is up to 15
// degrees off the circle's tangent) the tangent at every hit is within 1
// degree of the circle's tangent at that hit's angle, continuous across the
// joints, and orthogonal to the normal; so is an open arc of it, up to its
// ends.
TEST(TubeAccel, ShadingTangentFollowsTheCurveNotTheSegment) {
    for (const bool closed : {true, false}) {
        SCOPED_TRACE(closed ? "closed ring" : "open arc");
        Tube tube = ringTube(1.0, 0.05, 12);
        if (!closed) {
            tube.closed = false;
            tube.points.resize(7);  // the arc from 0 to 180 degrees
            tube.radii.resize(7);
        }
        TubeAccel accel;
        accel.addGeometry({tube}, 0);
        accel.commit();
        const int segments = closed ? 12 : 6;
        double worstSmooth = 0, worstSegment = 0;
        Vec3 previous;
        for (int k = 0; k < segments; ++k)
            for (const double u : {0.02, 0.25, 0.5, 0.75, 0.98}) {
                const Vec3& a = tube.points[k];
                const Vec3& b = tube.points[(k + 1) % 12];
                const Vec3 p = a * (1 - u) + b * u;
                TubeHit hit;
                ASSERT_TRUE(accel.intersect(p + Vec3(0, 0, 1), {0, 0, -1}, kInf, {}, &hit));
                const double angle = std::atan2(p.y, p.x);
                const Vec3 circle{-std::sin(angle), std::cos(angle), 0.0};
                const double smooth = std::acos(std::min(1.0, std::abs(dot(hit.tangent, circle))));
                const double segment =
                    std::acos(std::min(1.0, std::abs(dot(normalize(b - a), circle))));
                worstSmooth = std::max(worstSmooth, smooth);
                worstSegment = std::max(worstSegment, segment);
                EXPECT_NEAR(dot(hit.tangent, hit.normal), 0.0, 1e-9);
                EXPECT_NEAR(length(hit.tangent), 1.0, 1e-12);
                // Across a joint (u = 0.98 on one segment, 0.02 on the next):
                // the tangent moves by the 1.2 degrees the curve turns, not 30.
                if (u == 0.02 && k > 0) {
                    EXPECT_LT(std::acos(std::min(1.0, dot(hit.tangent, previous))), 0.03);
                }
                previous = hit.tangent;
            }
        EXPECT_LT(worstSmooth * 180 / kPi, 1.0);
        EXPECT_GT(worstSegment * 180 / kPi, 13.0);  // the facets the test would see
    }
}

// Where light leaves a tube (issue 47): walked along the centre line by tube
// radii, turned about it, carried along without twisting, stopped at an open
// end, wrapped round a closed loop.
TEST(TubeAccel, ExitPointWalksAlongTurnsAroundAndStopsAtAnOpenEnd) {
    TubeAccel accel;
    accel.addGeometry({straightTube(0.0, 0.5)}, 0);  // along +x, segments of length 1
    accel.commit();
    TubeHit hit;
    ASSERT_TRUE(accel.intersect({0.3, 0.0, 5.0}, {0.0, 0.0, -1.0}, kInf, {}, &hit));
    EXPECT_NEAR(hit.normal.z, 1.0, 1e-6);
    EXPECT_EQ(hit.segment, 4u);
    EXPECT_NEAR(hit.u, 0.3, 1e-6);
    // 1.5 radii (0.75) along +x, a quarter turn from n = +z towards t x n = -y.
    TubeHit exit = accel.exitPoint(hit, 1.5, kHalfPi);
    EXPECT_NEAR(exit.point.x, 1.05, 1e-6);
    EXPECT_NEAR(exit.point.y, -0.5, 1e-6);
    EXPECT_NEAR(exit.point.z, 0.0, 1e-6);
    EXPECT_NEAR(exit.normal.y, -1.0, 1e-6);
    EXPECT_NEAR(exit.tangent.x, 1.0, 1e-6);
    EXPECT_EQ(exit.segment, 5u);
    EXPECT_EQ(exit.id, hit.id);
    // Backwards across three segments, half a turn.
    exit = accel.exitPoint(hit, -5.0, kPi);
    EXPECT_NEAR(exit.point.x, -2.2, 1e-6);
    EXPECT_NEAR(exit.point.z, -0.5, 1e-6);
    EXPECT_EQ(exit.segment, 1u);
    // No offset: the hit itself (on the tube's surface).
    exit = accel.exitPoint(hit, 0.0, 0.0);
    EXPECT_NEAR(length(exit.point - hit.point), 0.0, 1e-6);
    // Past an open end: its last cross-section, finite.
    for (const double axial : {100.0, -1e9}) {
        exit = accel.exitPoint(hit, axial, 0.3);
        EXPECT_NEAR(exit.point.x, axial > 0 ? 4.0 : -4.0, 1e-6) << axial;
        EXPECT_NEAR(length(Vec3{0, exit.point.y, exit.point.z}), 0.5, 1e-6);
    }

    // A closed ring of 64 segments: a quarter of its length round from the
    // outermost point lands a quarter round, the normal still pointing
    // outwards (carried without twisting in the ring's plane); the whole
    // length comes back.
    TubeAccel ring;
    ring.addGeometry({ringTube(3.0, 0.25, 64)}, 0);
    ring.commit();
    ASSERT_TRUE(ring.intersect({8.0, 0.0, 0.0}, {-1.0, 0.0, 0.0}, kInf, {}, &hit));
    const double chord = 2 * 3.0 * std::sin(kPi / 64), circumference = 64 * chord;
    const double direction = hit.tangent.y > 0 ? 1.0 : -1.0;  // towards +y
    exit = ring.exitPoint(hit, direction * 0.25 * circumference / 0.25, 0.0);
    EXPECT_NEAR(exit.point.x, 0.0, 1e-5);
    EXPECT_NEAR(exit.point.y, 3.25, 1e-5);
    EXPECT_NEAR(exit.normal.y, 1.0, 1e-6);
    exit = ring.exitPoint(hit, direction * 2.0 * circumference / 0.25, 0.0);
    EXPECT_NEAR(length(exit.point - hit.point), 0.0, 1e-4);
}

TEST(TubeAccel, TubesWithinOneGeometryAreTold) {
    TubeAccel accel;
    accel.addGeometry(
        {straightTube(0.0, 0.2, 3), straightTube(1.0, 0.2, 5), straightTube(2.0, 0.2, 1)}, 3);
    accel.commit();
    EXPECT_EQ(accel.tubeCount(), 3);
    EXPECT_EQ(accel.segmentCount(), 9);
    EXPECT_GT(accel.embreeBytes(), 0);
    TubeHit hit;
    ASSERT_TRUE(accel.intersect({0.0, 0.0, 1.5}, {0, 0, -1}, kInf, {}, &hit));
    EXPECT_EQ(hit.id.tube, 1u);
    // Leaving tube 1 downwards: tube 0 of the same geometry is hit.
    ASSERT_TRUE(accel.intersect(hit.point, {0, 0, -1}, kInf, hit.id, &hit));
    EXPECT_EQ(hit.id.tube, 0u);
    ASSERT_TRUE(accel.intersect({3.5, 0.0, 5.0}, {0, 0, -1}, kInf, {}, &hit));
    EXPECT_EQ(hit.id.tube, 2u);
}

}  // namespace
}  // namespace weft::render
