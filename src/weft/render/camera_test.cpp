// Tests for weft/render/camera.h: the view axes, the film extent and the
// primary rays follow the documented pinhole convention.
#include "weft/render/camera.h"

#include <gtest/gtest.h>

#include <cmath>

#include "weft/core/math.h"

namespace weft::render {
namespace {

void expectNear(const Vec3& a, const Vec3& b, double tol) {
    EXPECT_NEAR(a.x, b.x, tol);
    EXPECT_NEAR(a.y, b.y, tol);
    EXPECT_NEAR(a.z, b.z, tol);
}

TEST(Camera, ViewAxesAreOrthonormalWithUpInTheImageVertical) {
    const Vec3 forward{1, -2, 0.5}, up{0.1, 1, 0};
    const ViewAxes a = viewAxes(forward * 3.0, up);
    expectNear(a.forward, forward / length(forward), 1e-15);
    for (const Vec3& v : {a.forward, a.right, a.up}) EXPECT_NEAR(length(v), 1.0, 1e-15);
    EXPECT_NEAR(dot(a.forward, a.right), 0.0, 1e-15);
    EXPECT_NEAR(dot(a.forward, a.up), 0.0, 1e-15);
    EXPECT_NEAR(dot(a.right, a.up), 0.0, 1e-15);
    // right x up = -forward (the camera looks down -z of its right-handed frame).
    expectNear(cross(a.right, a.up), -a.forward, 1e-15);
    // up' lies in the plane of forward and up, on the side of up.
    EXPECT_NEAR(dot(a.up, cross(forward, up)), 0.0, 1e-15);
    EXPECT_GT(dot(a.up, up), 0.0);
    // The default camera: looking down -z with +y up, +x to the right.
    const ViewAxes d = viewAxes({0, 0, -1}, {0, 1, 0});
    expectNear(d.right, {1, 0, 0}, 0);
    expectNear(d.up, {0, 1, 0}, 0);
}

TEST(Camera, FovSpansTheShorterSide) {
    const double t = std::tan(radians(20.0));
    const FilmExtent wide = filmExtent(40.0, 200, 100), tall = filmExtent(40.0, 100, 200);
    EXPECT_DOUBLE_EQ(wide.halfHeight, t);
    EXPECT_DOUBLE_EQ(wide.halfWidth, 2 * t);
    EXPECT_DOUBLE_EQ(tall.halfWidth, t);
    EXPECT_DOUBLE_EQ(tall.halfHeight, 2 * t);
}

TEST(Camera, RaysThroughTheCentreAndTheCorners) {
    CameraDesc desc;
    desc.from = {1, 2, 3};
    desc.to = {1, 2, -1};
    desc.fovDeg = 90;
    const Camera camera(desc, 40, 20);
    Vec3 org, dir;
    camera.ray(20, 10, &org, &dir);
    EXPECT_EQ(org, desc.from);
    expectNear(dir, {0, 0, -1}, 1e-15);
    // Pixel (0, 0) at the top left: half-extents 2 (width) and 1 (height).
    camera.ray(0, 0, &org, &dir);
    expectNear(dir, normalize({-2, 1, -1}), 1e-15);
    camera.ray(40, 20, &org, &dir);
    expectNear(dir, normalize({2, -1, -1}), 1e-15);
}

}  // namespace
}  // namespace weft::render
