// Tests of the generated scenes: yarns that touch but never intersect (brute
// force over every pair of polyline segments), a camera that sees every yarn,
// files that read back with the renderer's readers, determinism and input checks.
#include "weft/eval/scene_gen.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "weft/core/file.h"
#include "weft/core/math.h"
#include "weft/core/test_util.h"
#include "weft/render/curve_report.h"
#include "weft/render/environment_light.h"
#include "weft/render/scene.h"
#include "weft/render/sphere_light.h"

namespace weft::eval {
namespace {

using testing::expectInputError;

const std::string kFleece = std::string(WEFT_SOURCE_DIR) + "/tests/data/fleece-small.json";

SceneOptions options(int size = 6) {
    SceneOptions o;
    o.model = kFleece;
    o.size = size;
    return o;
}

// Distance between segments [p0, p1] and [q0, q1] (Ericson, Real-Time
// Collision Detection, 5.1.9: closest points of two segments).
double segmentDistance(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
    const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
    const double a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
    double s = 0, t = 0;
    if (a <= 0 && e <= 0) return length(r);
    if (a <= 0) {
        t = std::clamp(f / e, 0.0, 1.0);
    } else {
        const double c = dot(d1, r);
        if (e <= 0) {
            s = std::clamp(-c / a, 0.0, 1.0);
        } else {
            const double b = dot(d1, d2), denom = a * e - b * b;
            s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
            t = (b * s + f) / e;
            if (t < 0) {
                t = 0;
                s = std::clamp(-c / a, 0.0, 1.0);
            } else if (t > 1) {
                t = 1;
                s = std::clamp((b - c) / a, 0.0, 1.0);
            }
        }
    }
    return length((p0 + d1 * s) - (q0 + d2 * t));
}

// Smallest distance between two different polylines (every segment pair).
double curveDistance(const Curve& a, const Curve& b) {
    double best = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i + 1 < a.points.size(); ++i)
        for (size_t j = 0; j + 1 < b.points.size(); ++j)
            best = std::min(
                best, segmentDistance(a.points[i], a.points[i + 1], b.points[j], b.points[j + 1]));
    return best;
}

double minDistanceBetweenCurves(const CurveSet& set) {
    double best = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < set.curves.size(); ++i)
        for (size_t j = i + 1; j < set.curves.size(); ++j)
            best = std::min(best, curveDistance(set.curves[i], set.curves[j]));
    return best;
}

// Smallest distance between segments of one curve that are more than `gap`
// apart along it (a tube of radius R is free of self-intersection when this
// is >= 2 R for gap = pi R: the chord of an arc of length pi R bent at
// curvature radius rho >= R is >= 2 R).
double selfDistance(const Curve& c, double gap) {
    std::vector<double> arc(c.points.size(), 0.0);
    for (size_t i = 1; i < c.points.size(); ++i)
        arc[i] = arc[i - 1] + length(c.points[i] - c.points[i - 1]);
    double best = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i + 1 < c.points.size(); ++i)
        for (size_t j = i + 1; j + 1 < c.points.size(); ++j)
            if (arc[j] - arc[i + 1] > gap)
                best = std::min(best, segmentDistance(c.points[i], c.points[i + 1], c.points[j],
                                                      c.points[j + 1]));
    return best;
}

double minSelfDistance(const CurveSet& set, double gap) {
    double best = std::numeric_limits<double>::infinity();
    for (const Curve& c : set.curves) best = std::min(best, selfDistance(c, gap));
    return best;
}

// Film position of p with the pinhole of render::Camera (scene.h), computed
// here independently; `depth` is the distance along the view axis.
struct FilmPoint {
    double px = 0, py = 0, depth = 0;
};
FilmPoint project(const render::CameraDesc& cam, int width, int height, const Vec3& p) {
    const Vec3 f = normalize(cam.to - cam.from);
    const Vec3 r = normalize(cross(f, cam.up));
    const Vec3 u = cross(r, f);
    const double half = std::tan(0.5 * radians(cam.fovDeg));
    const double aspect = static_cast<double>(width) / height;
    const double hw = aspect >= 1 ? half * aspect : half, hh = aspect >= 1 ? half : half / aspect;
    const Vec3 q = p - cam.from;
    FilmPoint fp;
    fp.depth = dot(q, f);
    fp.px = (dot(q, r) / fp.depth / hw + 1) * 0.5 * width;
    fp.py = (1 - dot(q, u) / fp.depth / hh) * 0.5 * height;
    return fp;
}

// The renderer's primary ray through a point's film position points at it
// (so `project` is the renderer's convention), checked on the curves' points
// that are in view.
void expectProjectionMatchesCamera(const GeneratedScene& g) {
    const render::SceneDesc& s = g.scene;
    const render::Camera camera(s.camera, s.film.width, s.film.height);
    int checked = 0;
    for (const Curve& c : g.curves.curves)
        for (const Vec3& p : c.points) {
            const FilmPoint fp = project(s.camera, s.film.width, s.film.height, p);
            if (fp.depth <= 0 || fp.px < 0 || fp.px > s.film.width || fp.py < 0 ||
                fp.py > s.film.height || checked++ % 17 != 0)
                continue;
            Vec3 org, dir;
            camera.ray(fp.px, fp.py, &org, &dir);
            EXPECT_NEAR(length(dir - normalize(p - org)), 0.0, 1e-9);
        }
    EXPECT_GT(checked, 0);
}

// No yarn end (a ball of radius R around the end point: the cap) reaches the
// film: sampled on a dense grid of the ball's surface with `project`.
void expectEndsOutOfView(const GeneratedScene& g) {
    const render::SceneDesc& s = g.scene;
    const double radius = *s.yarns[0].radius;
    for (const Curve& c : g.curves.curves)
        for (const Vec3& end : {c.points.front(), c.points.back()})
            for (int i = 0; i <= 12; ++i)
                for (int j = 0; j < 24; ++j) {
                    const double theta = kPi * i / 12, phi = kTwoPi * j / 24;
                    const Vec3 p =
                        end + radius * Vec3{std::sin(theta) * std::cos(phi),
                                            std::sin(theta) * std::sin(phi), std::cos(theta)};
                    const FilmPoint fp = project(s.camera, s.film.width, s.film.height, p);
                    const bool inView = fp.depth > 0 && fp.px >= 0 && fp.px <= s.film.width &&
                                        fp.py >= 0 && fp.py <= s.film.height;
                    ASSERT_FALSE(inView) << "yarn end (" << end.x << ", " << end.y << ", " << end.z
                                         << ") is in view";
                }
}

// The rays through the film's corners (and centre) hit the cloth's plane
// z = 0 inside the rectangle the view must show.
void expectFilmCovered(const GeneratedScene& g, double x0, double x1, double y0, double y1) {
    const render::SceneDesc& s = g.scene;
    const render::Camera camera(s.camera, s.film.width, s.film.height);
    const double w = s.film.width, h = s.film.height;
    for (const auto& [px, py] : {std::pair{0.0, 0.0}, {w, 0.0}, {0.0, h}, {w, h}, {w / 2, h / 2}}) {
        Vec3 org, dir;
        camera.ray(px, py, &org, &dir);
        ASSERT_LT(dir.z, 0);
        const Vec3 hit = org + (-org.z / dir.z) * dir;
        EXPECT_GE(hit.x, x0 - 1e-9);
        EXPECT_LE(hit.x, x1 + 1e-9);
        EXPECT_GE(hit.y, y0 - 1e-9);
        EXPECT_LE(hit.y, y1 + 1e-9);
    }
}

TEST(SceneGen, WeaveTouchesWithoutIntersecting) {
    const SceneOptions o = options(6);
    const GeneratedScene g = weaveScene(o);
    // 6 warp and 6 weft yarns in view, as many more around them as hide the ends.
    ASSERT_GE(g.curves.curves.size(), 12u);
    ASSERT_EQ(g.curves.curves.size() % 2, 0u);
    const double twoR = 2 * o.radius;
    const double between = minDistanceBetweenCurves(g.curves);
    std::printf("weave: min distance between yarns = %.5f (2R), self = %.4f (2R)\n", between / twoR,
                minSelfDistance(g.curves, kPi * o.radius) / twoR);
    EXPECT_GE(between, twoR);
    EXPECT_LE(between, 1.02 * twoR);  // touching: the 1% clearance and sampling only
    EXPECT_GE(minSelfDistance(g.curves, kPi * o.radius), twoR);
    // Parallel neighbours are one spacing apart, crossings 2 A apart.
    const WeaveGeometry w = weaveGeometry(o.radius);
    EXPECT_NEAR(curveDistance(g.curves.curves[0], g.curves.curves[1]), w.spacing, 1e-12);
    EXPECT_NEAR(w.spacing, kPi * std::sqrt(2.0) * w.amplitude, 1e-15);
}

TEST(SceneGen, WeaveDerivationHoldsOnTheContinuousCurves) {
    // D^2(u, v) = u^2 + v^2 + A^2 (cos ku + cos kv)^2 >= 4 A^2 on a fine grid of
    // one cell (beyond |u|, |v| > d the u^2 + v^2 term alone exceeds it).
    const WeaveGeometry w = weaveGeometry(1.0);
    const double d = w.spacing, a = w.amplitude, k = kPi / d;
    double best = std::numeric_limits<double>::infinity();
    const int n = 800;
    for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
            const double u = d * i / n, v = d * j / n;
            const double c = std::cos(k * u) + std::cos(k * v);
            best = std::min(best, u * u + v * v + a * a * c * c);
        }
    EXPECT_NEAR(std::sqrt(best), 2 * a, 1e-12);
    // A denser weave (d below pi sqrt(2) A) brings crossing yarns closer than 2 A.
    // Along the diagonal u = v: D^2 = 2 u^2 + 4 A^2 cos^2(ku) dips below 4 A^2.
    const double dense = 0.9 * d, kd = kPi / dense;
    double diagonal = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= n; ++i) {
        const double u = 0.5 * dense * i / n, c = 2 * std::cos(kd * u);
        diagonal = std::min(diagonal, 2 * u * u + a * a * c * c);
    }
    EXPECT_LT(std::sqrt(diagonal), 2 * a);
}

TEST(SceneGen, KnitCoursesDoNotIntersect) {
    const SceneOptions o = options(4);
    const GeneratedScene g = knitScene(o);
    // The 4 courses of the view, one more above and below, and as many more
    // courses and loops around them as hide the ends.
    ASSERT_GE(g.curves.curves.size(), 6u);
    const size_t extra = (g.curves.curves.size() - 6) / 2;
    ASSERT_EQ(g.curves.curves[0].points.size(), (4 + 2 * extra) * kKnitSamplesPerLoop + 1);
    const double twoR = 2 * o.radius;
    const double between = minDistanceBetweenCurves(g.curves);
    const double self = minSelfDistance(g.curves, kPi * o.radius);
    std::printf("knit: min distance between courses = %.5f (2R), self (> pi R apart) = %.5f (2R)\n",
                between / twoR, self / twoR);
    EXPECT_GE(between, twoR);
    EXPECT_LE(between, 1.05 * twoR);  // neighbouring courses touch (within 5%)
    EXPECT_GE(self, twoR);
    // Courses interlock: each overlaps its neighbour in y by more than 2 R.
    const Bounds3 b0 = bounds({{g.curves.curves[0]}});
    const Bounds3 b1 = bounds({{g.curves.curves[1]}});
    EXPECT_GT(b0.hi.y - b1.lo.y, twoR);
}

TEST(SceneGen, CloseupIsOneOpenYarnAcrossTheFrame) {
    const SceneOptions o = options();
    const GeneratedScene g = closeupScene(o);
    ASSERT_EQ(g.curves.curves.size(), 1u);
    EXPECT_FALSE(g.curves.curves[0].closed);
    EXPECT_GE(minSelfDistance(g.curves, kPi * o.radius), 2 * o.radius);
    expectProjectionMatchesCamera(g);
    expectEndsOutOfView(g);
    // The framed 8 R (x in [-4 R, 4 R]) spans the film: its ends project
    // near the left and right edges, and the yarn runs on beyond both.
    const render::SceneDesc& s = g.scene;
    const double len = 8 * o.radius;
    const auto atX = [&](double x) {
        return Vec3{x, 0.08 * len * std::cos(kPi * x / len), 0.04 * len * std::sin(kPi * x / len)};
    };
    const FilmPoint left = project(s.camera, 512, 512, atX(-0.5 * len));
    const FilmPoint right = project(s.camera, 512, 512, atX(0.5 * len));
    EXPECT_LT(left.px, 0.2 * 512);
    EXPECT_GT(left.px, 0);
    EXPECT_GT(right.px, 0.8 * 512);
    EXPECT_LT(right.px, 512);
    EXPECT_LT(g.curves.curves[0].points.front().x, -0.5 * len);
    EXPECT_GT(g.curves.curves[0].points.back().x, 0.5 * len);
}

TEST(SceneGen, ClothFillsTheFrameAndEndsStayOutOfViewOnAnyFilm) {
    for (const SceneKind kind : {SceneKind::Closeup, SceneKind::Weave, SceneKind::Knit}) {
        for (const auto& [w, h] : {std::pair{512, 512}, {640, 200}, {200, 640}, {1, 1}}) {
            SCOPED_TRACE(std::string(sceneKindName(kind)) + " " + std::to_string(w) + "x" +
                         std::to_string(h));
            SceneOptions o = options(3);
            o.width = w;
            o.height = h;
            const GeneratedScene g = generateScene(kind, o);
            EXPECT_EQ(g.scene.film.width, w);
            EXPECT_EQ(g.scene.film.height, h);
            expectEndsOutOfView(g);
            if (kind == SceneKind::Weave) {
                const double d = weaveGeometry(o.radius).spacing;
                expectFilmCovered(g, -0.5 * d, 2.5 * d, -0.5 * d, 2.5 * d);
            } else if (kind == SceneKind::Knit) {
                const KnitGeometry k = knitGeometry(o.radius);
                expectFilmCovered(g, 0, 3 * kTwoPi * k.scale, -0.5 * k.rowSpacing * k.scale,
                                  2.5 * k.rowSpacing * k.scale);
            }
        }
    }
}

// Issue 41: a weave on a 1 x 512 film never finished: every margin tried
// generated the whole patch, and no margin could hide the ends of a view that
// looks past the cloth. Now the extreme shapes in range finish with a
// bounded margin, and those beyond it are refused with their shape.
TEST(SceneGen, ExtremeFilmShapesInRangeFrameWithABoundedMargin) {
    const int wide = static_cast<int>(kMaxFilmAspect);
    const int tall = static_cast<int>(kMaxPatchFilmTallness);
    for (const SceneKind kind : {SceneKind::Closeup, SceneKind::Weave, SceneKind::Knit}) {
        std::vector<std::pair<int, int>> shapes = {
            {1, 1}, {2, 1}, {1, 2}, {wide, 1}, {163 * wide, 163}, {16384, 16384}};
        if (kind == SceneKind::Closeup) {
            shapes.insert(shapes.end(), {{1, 16384}, {1, 512}, {2, 512}, {1, 16}});
        } else {
            shapes.insert(shapes.end(), {{1, tall}, {1638, 1638 * tall}, {3, 3 * tall}});
        }
        for (const int size : {1, 2, 3}) {
            if (kind == SceneKind::Closeup && size > 1) continue;
            for (const auto& [w, h] : shapes) {
                SCOPED_TRACE(std::string(sceneKindName(kind)) + " " + std::to_string(w) + "x" +
                             std::to_string(h) + " size " + std::to_string(size));
                SceneOptions o = options(size);
                o.width = w;
                o.height = h;
                const GeneratedScene g = generateScene(kind, o);
                EXPECT_GE(g.endMargin, 0);
                EXPECT_LE(g.endMargin, kMaxEndMargin / 2);
                expectEndsOutOfView(g);
                if (kind == SceneKind::Weave) {
                    const double d = weaveGeometry(o.radius).spacing;
                    expectFilmCovered(g, -0.5 * d, (size - 0.5) * d, -0.5 * d, (size - 0.5) * d);
                } else if (kind == SceneKind::Knit) {
                    const KnitGeometry k = knitGeometry(o.radius);
                    expectFilmCovered(g, 0, size * kTwoPi * k.scale, -0.5 * k.rowSpacing * k.scale,
                                      (size - 0.5) * k.rowSpacing * k.scale);
                }
            }
        }
    }
    // A larger patch at the widest and tallest films (the margin, in yarns
    // and loops, shrinks as the patch grows: docs/scenes.md).
    for (const auto& [w, h] : {std::pair{wide, 1}, {1, tall}}) {
        SceneOptions o = options(12);
        o.width = w;
        o.height = h;
        EXPECT_LE(weaveScene(o).endMargin, kMaxEndMargin / 2);
        EXPECT_LE(knitScene(o).endMargin, kMaxEndMargin / 2);
    }
}

TEST(SceneGen, FilmsTooWideOrTooTallToFrameAreRefusedWithTheirShape) {
    struct Case {
        SceneKind kind;
        int width, height;
        std::vector<std::string> parts;
    };
    const std::string tallParts = "times as tall as wide";
    const std::vector<Case> cases = {
        {SceneKind::Weave, 1, 512, {"--width 1 --height 512", "512 times as tall", "at most 10"}},
        {SceneKind::Weave, 2, 512, {"--width 2 --height 512", "256 times as tall"}},
        {SceneKind::Weave, 1, 16, {"--width 1 --height 16", "a weave allows at most 10"}},
        {SceneKind::Knit, 1, 16, {"--width 1 --height 16", "a knit allows at most 10"}},
        {SceneKind::Knit, 1, 11, {"--width 1 --height 11", tallParts}},
        {SceneKind::Weave, 16384, 1, {"--width 16384 --height 1", "16384 times as wide",
                                      "at most 100"}},
        {SceneKind::Knit, 16384, 1, {"--width 16384 --height 1", "at most 100"}},
        {SceneKind::Closeup, 16384, 1, {"--width 16384 --height 1", "at most 100"}},
        {SceneKind::Closeup, 101, 1, {"--width 101 --height 1", "101 times as wide"}},
    };
    for (const Case& c : cases) {
        SceneOptions o = options(2);
        o.width = c.width;
        o.height = c.height;
        for (const std::string& part : c.parts)
            expectInputError([&] { generateScene(c.kind, o); }, {part});
    }
}

TEST(SceneGen, FrameCoverIsTight) {
    // A square seen head-on fills a square film exactly: the corner rays land
    // on its corners.
    const render::CameraDesc cam = frameCover(-1, 1, -1, 1, {0, 0, -1}, 30, 100, 100);
    EXPECT_NEAR(length(cam.from - Vec3{0, 0, 1 / std::tan(radians(15))}), 0, 1e-9);
    const FilmPoint corner = project(cam, 100, 100, {1, 1, 0});
    EXPECT_NEAR(corner.px, 100, 1e-6);
    EXPECT_NEAR(corner.py, 0, 1e-6);
}

TEST(SceneGen, OutOfViewIsTheWholeBall) {
    render::CameraDesc cam;
    cam.from = {0, 0, 10};
    cam.to = {0, 0, 0};
    // The film's right edge on the plane z = 0 is at x = 10 tan 15 degrees.
    const double edge = 10 * std::tan(radians(15));
    EXPECT_FALSE(outOfView(cam, 64, 64, {edge + 0.5, 0, 0}, 1.0));  // the ball straddles the edge
    EXPECT_TRUE(outOfView(cam, 64, 64, {edge + 1.5, 0, 0}, 1.0));
    EXPECT_FALSE(outOfView(cam, 64, 64, {0, 0, 0}, 0.1));
    EXPECT_TRUE(outOfView(cam, 64, 64, {0, 0, 12}, 1.0));     // behind the camera
    EXPECT_FALSE(outOfView(cam, 64, 64, {0, 0, 10.5}, 1.0));  // around the camera
}

TEST(SceneGen, FrameBoxIsTight) {
    // A flat square seen head-on touches the frame on all four sides.
    Bounds3 box;
    box.extend({-1, -1, 0});
    box.extend({1, 1, 0});
    const render::CameraDesc cam = frameBox(box, {0, 0, -1}, 30, 100, 100, 1.0);
    const FilmPoint corner = project(cam, 100, 100, {1, 1, 0});
    EXPECT_NEAR(corner.px, 100, 1e-9);
    EXPECT_NEAR(corner.py, 0, 1e-9);
    EXPECT_NEAR(length(cam.from - Vec3{0, 0, 1 / std::tan(radians(15))}), 0, 1e-12);
}

TEST(SceneGen, LightsAreTheSkyAndTwoSpheresOutOfView) {
    const GeneratedScene g = weaveScene(options(3));
    const render::SceneDesc& s = g.scene;
    ASSERT_EQ(s.lights.size(), 3u);
    EXPECT_STREQ(s.lights[0]->type(), "sky");
    const double distance = length(s.camera.to - s.camera.from);
    for (int i : {1, 2}) {
        ASSERT_STREQ(s.lights[i]->type(), "sphere");
        const auto& l = s.lights[i]->as<render::SphereLightDesc>();
        // Bright enough for highlights: brighter than the sky (order 1).
        EXPECT_GT(l.radiance.maxComponent(), 10);
        // Neither encloses the camera nor any yarn.
        EXPECT_GT(length(l.center - s.camera.from), l.radius);
        EXPECT_GT(length(l.center - s.camera.to), l.radius + 0.5 * distance);
        // Off the film (its centre outside the image by more than its radius).
        const FilmPoint fp = project(s.camera, 512, 512, l.center);
        EXPECT_TRUE(fp.depth < 0 || fp.px < 0 || fp.px > 512 || fp.py < 0 || fp.py > 512);
    }
    // Key top-right, fill bottom-left of the view.
    const auto& keyLight = s.lights[1]->as<render::SphereLightDesc>();
    const auto& fillLight = s.lights[2]->as<render::SphereLightDesc>();
    const FilmPoint key = project(s.camera, 512, 512, keyLight.center);
    const FilmPoint fill = project(s.camera, 512, 512, fillLight.center);
    EXPECT_GT(key.px, 512);
    EXPECT_LT(key.py, 0);
    EXPECT_LT(fill.px, 0);
    EXPECT_GT(fill.py, 512);
    EXPECT_GT(keyLight.radiance.average(), fillLight.radiance.average());
}

class SceneGenFiles : public testing::TempDirTest {};

TEST_F(SceneGenFiles, WrittenFilesReadBack) {
    for (const SceneKind kind : {SceneKind::Closeup, SceneKind::Weave, SceneKind::Knit}) {
        SCOPED_TRACE(sceneKindName(kind));
        SceneOptions o = options(3);
        o.radius = 0.02;
        o.plies = 2;
        o.plyTwist = -0.5;
        o.width = 320;
        o.height = 240;
        o.spp = 7;
        const GeneratedScene g = generateScene(kind, o);
        const std::string dir = path(sceneKindName(kind));
        writeScene(g, dir);

        const render::SceneDesc s = render::loadScene(dir + "/scene.json");
        EXPECT_EQ(s.film.width, 320);
        EXPECT_EQ(s.film.height, 240);
        EXPECT_EQ(s.render.spp, 7);
        EXPECT_EQ(s.camera.fovDeg, g.scene.camera.fovDeg);
        EXPECT_NEAR(length(s.camera.from - g.scene.camera.from), 0, 1e-12);
        ASSERT_EQ(s.yarns.size(), 1u);
        EXPECT_EQ(std::filesystem::path(s.yarns[0].curves),
                  std::filesystem::path(dir) / "yarns.txt");
        EXPECT_EQ(std::filesystem::path(s.yarns[0].model),
                  std::filesystem::absolute(kFleece).lexically_normal());
        EXPECT_EQ(*s.yarns[0].radius, 0.02);
        EXPECT_EQ(s.yarns[0].plies, 2);
        EXPECT_EQ(s.yarns[0].plyTwist, -0.5);
        EXPECT_EQ(s.lights.size(), 3u);

        const CurveSet read = readCurves(s.yarns[0].curves);
        ASSERT_EQ(read.curves.size(), g.curves.curves.size());
        for (size_t c = 0; c < read.curves.size(); ++c) {
            ASSERT_EQ(read.curves[c].points.size(), g.curves.curves[c].points.size());
            EXPECT_FALSE(read.curves[c].closed);
            EXPECT_TRUE(read.curves[c].radii.empty());
            for (size_t i = 0; i < read.curves[c].points.size(); ++i)
                ASSERT_LE(length(read.curves[c].points[i] - g.curves.curves[c].points[i]),
                          1e-8 * (length(g.curves.curves[c].points[i]) + o.radius));
        }
        // Only the two files, no leftovers beside or inside.
        std::vector<std::string> names;
        for (const auto& e : std::filesystem::directory_iterator(dir))
            names.push_back(e.path().filename());
        std::sort(names.begin(), names.end());
        EXPECT_EQ(names, (std::vector<std::string>{"scene.json", "yarns.txt"}));
    }
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir_),
                            std::filesystem::directory_iterator()),
              3);
}

TEST_F(SceneGenFiles, Deterministic) {
    for (const SceneKind kind : {SceneKind::Closeup, SceneKind::Weave, SceneKind::Knit}) {
        const GeneratedScene a = generateScene(kind, options(3));
        const GeneratedScene b = generateScene(kind, options(3));
        EXPECT_EQ(curvesText(a.curves), curvesText(b.curves));
        EXPECT_EQ(render::toJson(a.scene), render::toJson(b.scene));
        writeScene(a, path("a"));
        writeScene(b, path("b"));
        EXPECT_EQ(readFile(path("a/scene.json")), readFile(path("b/scene.json")));
        EXPECT_EQ(readFile(path("a/yarns.txt")), readFile(path("b/yarns.txt")));
    }
}

TEST_F(SceneGenFiles, ReplacesAnEarlierSceneOnly) {
    writeScene(weaveScene(options(2)), path("out"));
    writeScene(knitScene(options(2)), path("out"));  // an earlier scene is replaced
    EXPECT_EQ(readCurves(path("out/yarns.txt")).curves.size(),
              knitScene(options(2)).curves.curves.size());
    EXPECT_NE(knitScene(options(2)).curves.curves.size(),
              weaveScene(options(2)).curves.curves.size());
    writeFileAtomic(path("out/render.exr"), "x");
    expectInputError([&] { writeScene(weaveScene(options(2)), path("out")); },
                     {path("out"), "render.exr"});
    EXPECT_TRUE(std::filesystem::exists(path("out/render.exr")));
    writeFileAtomic(path("file"), "x");
    expectInputError([&] { writeScene(weaveScene(options(2)), path("file")); },
                     {path("file"), "not a directory"});
}

TEST_F(SceneGenFiles, EnvmapReplacesTheSky) {
    // A 4 x 2 Radiance map, flat RGBE texels of 1.0 (the upper-case
    // extension counts as .hdr).
    std::string hdr = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 4\n";
    for (int k = 0; k < 8; ++k) hdr += "\x80\x80\x80\x81";
    writeFileAtomic(path("studio.HDR"), hdr);
    SceneOptions o = options(2);
    o.envmap = path("studio.HDR");
    const GeneratedScene g = knitScene(o);
    ASSERT_EQ(g.scene.lights.size(), 3u);
    EXPECT_STREQ(g.scene.lights[0]->type(), "envmap");
    EXPECT_EQ(g.scene.lights[0]->as<render::EnvmapLightDesc>().file, path("studio.HDR"));
    o.envmap = path("missing.exr");
    expectInputError([&] { knitScene(o); }, {"--envmap", "missing.exr"});
    // The map is loaded as the renderer will load it: a header alone fails now.
    writeFileAtomic(path("cut.hdr"), "#?RADIANCE\n");
    o.envmap = path("cut.hdr");
    expectInputError([&] { knitScene(o); }, {"--envmap", "cut.hdr"});
    o.envmap = path("studio.png");
    expectInputError([&] { knitScene(o); }, {"--envmap", "studio.png", ".exr", ".hdr"});
}

TEST(SceneGen, OptionsAreRangeChecked) {
    struct Case {
        void (*set)(SceneOptions&);
        std::vector<std::string> parts;
    };
    const std::vector<Case> cases = {
        {[](SceneOptions& o) { o.size = 0; }, {"--size 0", "[1, 100]"}},
        {[](SceneOptions& o) { o.size = 101; }, {"--size 101", "[1, 100]"}},
        {[](SceneOptions& o) { o.radius = 0; }, {"--radius 0", "[1e-06, 1000]"}},
        {[](SceneOptions& o) { o.radius = std::nan(""); }, {"--radius nan"}},
        {[](SceneOptions& o) { o.radius = 2e3; }, {"--radius 2000"}},
        {[](SceneOptions& o) { o.plies = 0; }, {"--plies 0", "[1, 16]"}},
        {[](SceneOptions& o) { o.plies = 17; }, {"--plies 17", "[1, 16]"}},
        {[](SceneOptions& o) { o.plyTwist = 101; }, {"--ply-twist 101", "[-100, 100]"}},
        {[](SceneOptions& o) { o.width = 0; }, {"--width 0", "[1, 16384]"}},
        {[](SceneOptions& o) { o.height = 16385; }, {"--height 16385", "[1, 16384]"}},
        {[](SceneOptions& o) { o.spp = 0; }, {"--spp 0", "[1, 1048576]"}},
        {[](SceneOptions& o) { o.colours = {Rgb(0.5, 1.5, 0.5)}; }, {"--colours 1.5", "[0, 1]"}},
        {[](SceneOptions& o) {
             o.colours = {Rgb(0.5), Rgb(0.5, 0.5, std::nan(""))};
         },
         {"--colours nan", "[0, 1]"}},
        {[](SceneOptions& o) {
             o.colours = {Rgb(0.1), Rgb(0.2), Rgb(0.3)};
         },
         {"--colours", "one or two", "got 3"}},
        {[](SceneOptions& o) { o.stripe = 0; }, {"--stripe 0", "[1, 100]"}},
        {[](SceneOptions& o) {
             o.colours = {Rgb(0.5)};
             o.stripe = 3;
         },
         {"--stripe", "two --colours"}},
        {[](SceneOptions& o) {
             o.colours = {Rgb(0.1), Rgb(0.9)};
             o.stripe = 3;
             o.dyeLength = 4;
         },
         {"--stripe", "--dye-length", "exclude"}},
        {[](SceneOptions& o) { o.model.clear(); }, {"--model", "required"}},
        {[](SceneOptions& o) { o.model = "no-such-model.json"; },
         {"--model", "no-such-model.json"}},
        {[](SceneOptions& o) { o.model = std::string(WEFT_SOURCE_DIR) + "/tests/data/README.md"; },
         {"--model", "README.md"}},
    };
    for (const Case& c : cases) {
        for (const SceneKind kind : {SceneKind::Closeup, SceneKind::Weave, SceneKind::Knit}) {
            SceneOptions o = options(2);
            c.set(o);
            try {
                generateScene(kind, o);
                ADD_FAILURE() << "expected an InputError for " << c.parts[0];
            } catch (const InputError& e) {
                for (const std::string& p : c.parts)
                    EXPECT_NE(std::string(e.what()).find(p), std::string::npos)
                        << e.what() << " lacks " << p;
            }
        }
    }
}

// The stripe of integer position x (rounded) in stripes of `width`, counted
// from 0 at position 0 and negative below it, as floor(x / width).
int stripeOf(double x, int width) { return static_cast<int>(std::floor(std::round(x) / width)); }
bool isEven(int k) { return ((k % 2) + 2) % 2 == 0; }

TEST(SceneGen, TwoColoursMakeAStripedKnitAndACheckWeave) {
    const Rgb a(0.9, 0.2, 0.1), b(0.1, 0.3, 0.8);
    for (const int stripe : {1, 2, 3}) {
        SCOPED_TRACE(stripe);
        SceneOptions o = options(5);
        o.colours = {a, b};
        o.stripe = stripe;
        // Knit: course `row` (its mean y over whole loops is row * w * scale)
        // has colour a on even stripes of rows, b on odd ones.
        const GeneratedScene knit = knitScene(o);
        ASSERT_EQ(knit.scene.yarns.size(), 2u);
        EXPECT_EQ(*knit.scene.yarns[0].colour, a);
        EXPECT_EQ(*knit.scene.yarns[1].colour, b);
        EXPECT_EQ(knit.scene.yarns[0].curves, "yarns-1.txt");
        EXPECT_EQ(knit.scene.yarns[1].curves, "yarns-2.txt");
        const KnitGeometry g = knitGeometry(o.radius);
        int coursesOfB = 0;
        for (size_t c = 0; c < knit.curves.curves.size(); ++c) {
            const auto& points = knit.curves.curves[c].points;
            double y = 0;
            for (size_t i = 0; i + 1 < points.size(); ++i) y += points[i].y;  // whole loops
            const double row = y / (points.size() - 1) / (g.rowSpacing * g.scale);
            const Rgb want = isEven(stripeOf(row, stripe)) ? a : b;
            EXPECT_EQ(*knit.scene.yarns.at(knit.entryOfCurve.at(c)).colour, want) << row;
            coursesOfB += want == b;
        }
        EXPECT_GT(coursesOfB, 0);
        // Weave: warp along x at y = j d in colour a on even stripes of j;
        // weft along y at x = i d in colour b on even stripes of i.
        const GeneratedScene weave = weaveScene(o);
        ASSERT_EQ(weave.scene.yarns.size(), 2u);
        const double d = weaveGeometry(o.radius).spacing;
        int solidA = 0, solidB = 0, shot = 0;
        std::vector<Rgb> warp, weft;
        for (size_t c = 0; c < weave.curves.curves.size(); ++c) {
            const auto& points = weave.curves.curves[c].points;
            const bool isWarp = points.front().y == points.back().y;
            const double position = (isWarp ? points.front().y : points.front().x) / d;
            const bool even = isEven(stripeOf(position, stripe));
            const Rgb want = isWarp == even ? a : b;
            const Rgb got = *weave.scene.yarns.at(weave.entryOfCurve.at(c)).colour;
            EXPECT_EQ(got, want) << (isWarp ? "warp " : "weft ") << position;
            (isWarp ? warp : weft).push_back(got);
        }
        for (const Rgb& w : warp)
            for (const Rgb& f : weft) (w == f ? (w == a ? solidA : solidB) : shot) += 1;
        EXPECT_GT(solidA, 0);
        EXPECT_GT(solidB, 0);
        EXPECT_GT(shot, 0);
    }
}

TEST(SceneGen, OneColourColoursEveryYarnAndTheCloseupTakesOne) {
    SceneOptions o = options(3);
    o.colours = {Rgb(0.3, 0.6, 0.9)};
    for (const SceneKind kind : {SceneKind::Closeup, SceneKind::Weave, SceneKind::Knit}) {
        const GeneratedScene g = generateScene(kind, o);
        ASSERT_EQ(g.scene.yarns.size(), 1u);
        EXPECT_EQ(g.scene.yarns[0].curves, "yarns.txt");
        EXPECT_EQ(*g.scene.yarns[0].colour, Rgb(0.3, 0.6, 0.9));
        EXPECT_EQ(std::count(g.entryOfCurve.begin(), g.entryOfCurve.end(), 0),
                  static_cast<long>(g.curves.curves.size()));
    }
    EXPECT_FALSE(generateScene(SceneKind::Knit, options(3)).scene.yarns[0].colour);
    o.colours.push_back(Rgb(0.5));
    expectInputError([&] { closeupScene(o); }, {"--colours", "one yarn", "one colour"});
}

TEST(SceneGen, SpaceDyedYarnsAlternateEveryDyeLengthAlongTheCurve) {
    const Rgb a(0.9, 0.2, 0.1), b(0.1, 0.3, 0.8);
    for (const SceneKind kind : {SceneKind::Closeup, SceneKind::Weave, SceneKind::Knit}) {
        SCOPED_TRACE(sceneKindName(kind));
        SceneOptions o = options(3);
        o.colours = {a, b};
        o.dyeLength = 5;
        const GeneratedScene g = generateScene(kind, o);
        ASSERT_EQ(g.scene.yarns.size(), 1u);
        EXPECT_FALSE(g.scene.yarns[0].colour);
        EXPECT_EQ(g.scene.yarns[0].vertexColours, "colours.txt");
        const double stretch = 5 * o.radius;
        for (const Curve& c : g.curves.curves) {
            ASSERT_EQ(c.colours.size(), c.points.size());
            // Runs of one colour, alternating; every run but the first and
            // the last spans the dye length to within one point spacing.
            double runStart = 0, arc = 0, spacing = 0;
            int runs = 0;
            for (size_t i = 1; i < c.points.size(); ++i) {
                const double step = length(c.points[i] - c.points[i - 1]);
                arc += step;
                spacing = std::max(spacing, step);
                ASSERT_TRUE(c.colours[i] == a || c.colours[i] == b);
                if (c.colours[i] != c.colours[i - 1]) {
                    if (runs > 0) {
                        EXPECT_NEAR(arc - runStart, stretch, spacing + 1e-12);
                    }
                    ++runs;
                    runStart = arc;
                }
            }
            EXPECT_GE(runs, 2);
        }
    }
    // The pattern does not move with the film (the margin of hidden yarn).
    SceneOptions o = options(3);
    o.colours = {a, b};
    o.dyeLength = 5;
    const GeneratedScene square = knitScene(o);
    o.width = 900;
    const GeneratedScene wide = knitScene(o);
    // Courses that are the same row in both have the same colours where their points meet.
    size_t matched = 0;
    for (const Curve& c0 : square.curves.curves)
        for (const Curve& c1 : wide.curves.curves)
            for (size_t i = 0; i < c0.points.size(); i += 7)
                for (size_t j = 0; j < c1.points.size(); ++j)
                    if (length(c0.points[i] - c1.points[j]) < 1e-12) {
                        EXPECT_EQ(c0.colours[i], c1.colours[j]);
                        ++matched;
                    }
    EXPECT_GT(matched, 0u);
    // Two colours are needed, and a length in range.
    o.colours = {a};
    expectInputError([&] { knitScene(o); }, {"--dye-length", "two --colours"});
    o.colours = {a, b};
    o.dyeLength = 0.1;
    expectInputError([&] { knitScene(o); }, {"--dye-length 0.1", "[0.5, 10000]"});
    // Given is checked, 0 included (issue 41: 0 read as "not given" and made stripes).
    for (const double bad : {0.0, -0.0, -3.0}) {
        o.dyeLength = bad;
        for (const SceneKind kind : {SceneKind::Closeup, SceneKind::Weave, SceneKind::Knit})
            expectInputError([&] { generateScene(kind, o); }, {"--dye-length ", "[0.5, 10000]"});
    }
    o.colours = {a};
    o.dyeLength = 0.0;
    expectInputError([&] { knitScene(o); }, {"--dye-length 0", "[0.5, 10000]"});
}

TEST_F(SceneGenFiles, TwoColourFilesReadBackAsTwoEntries) {
    SceneOptions o = options(3);
    o.colours = {Rgb(0.8, 0.1, 0.1), Rgb(0.95)};
    const GeneratedScene g = knitScene(o);
    writeScene(weaveScene(options(2)), path("out"));
    writeScene(g, path("out"));  // replaces the one-colour scene, yarns.txt included
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(path("out")))
        names.push_back(e.path().filename());
    std::sort(names.begin(), names.end());
    EXPECT_EQ(names, (std::vector<std::string>{"scene.json", "yarns-1.txt", "yarns-2.txt"}));
    const render::SceneDesc s = render::loadScene(path("out/scene.json"));
    ASSERT_EQ(s.yarns.size(), 2u);
    size_t total = 0;
    for (int e = 0; e < 2; ++e) {
        EXPECT_EQ(*s.yarns[e].colour, o.colours[e]);
        const CurveSet read = readCurves(s.yarns[e].curves);
        EXPECT_EQ(read.curves.size(),
                  static_cast<size_t>(std::count(g.entryOfCurve.begin(), g.entryOfCurve.end(), e)));
        total += read.curves.size();
    }
    EXPECT_EQ(total, g.curves.curves.size());
    writeScene(weaveScene(options(2)), path("out"));  // and back: the yarns-N files go
    EXPECT_FALSE(std::filesystem::exists(path("out/yarns-1.txt")));
    // Space-dyed: the colour file reads back onto the curves.
    o.dyeLength = 3;
    const GeneratedScene dyed = closeupScene(o);
    writeScene(dyed, path("out"));
    const render::SceneDesc d = render::loadScene(path("out/scene.json"));
    ASSERT_EQ(d.yarns.size(), 1u);
    CurveSet read = readCurves(d.yarns[0].curves);
    render::readVertexColours(d.yarns[0].vertexColours, &read);
    ASSERT_EQ(read.curves.size(), 1u);
    EXPECT_EQ(read.curves[0].colours, dyed.curves.curves[0].colours);
    writeFileAtomic(path("out/yarns-x.txt"), "x");
    expectInputError([&] { writeScene(g, path("out")); }, {"yarns-x.txt"});
}

TEST(SceneGen, KindNames) {
    for (const SceneKind kind :
         {SceneKind::Closeup, SceneKind::Weave, SceneKind::Knit, SceneKind::Curves})
        EXPECT_EQ(parseSceneKind(sceneKindName(kind)), kind);
    expectInputError([] { parseSceneKind("twill"); }, {"twill", "closeup, weave, knit, curves"});
    for (const CurvesView view : {CurvesView::ThreeQuarter, CurvesView::Front, CurvesView::Top})
        EXPECT_EQ(parseCurvesView(curvesViewName(view)), view);
    expectInputError([] { parseCurvesView("side"); }, {"--view", "side", "three-quarter"});
}

// Issue 43, item 1: any curve file is framed whole from every view and film
// shape: every point of every curve, grown by the yarn radius, projects
// inside the film and in front of the camera; the radius is the largest
// without overlap (the scaled curves' closest contact is two radii).
TEST(SceneGen, CurveFilesAreFramedWholeFromEveryView) {
    for (const std::string name : {"knit-stockinette-tiny.bcc", "woven-satin-small.bcc"}) {
        const std::string file = std::string(WEFT_CURVE_DATA_DIR) + "/" + name;
        const render::CurveReport original = render::curveReport(readCurves(file));
        for (const CurvesView view : {CurvesView::ThreeQuarter, CurvesView::Front, CurvesView::Top})
            for (const auto& [w, h] : {std::pair{160, 120}, {90, 300}}) {
                SCOPED_TRACE(name + " " + curvesViewName(view) + " " + std::to_string(w));
                SceneOptions o = options();
                o.curves = file;
                o.view = view;
                o.width = w, o.height = h;
                const GeneratedScene g = curvesScene(o);
                EXPECT_EQ(g.curveRadiusSource, "largest_without_overlap");
                EXPECT_NEAR(g.curveRadius, original.largestRadiusWithoutOverlap(), 1e-12);
                EXPECT_NEAR(g.curveScale * g.curveRadius, o.radius, 1e-15);
                EXPECT_NEAR(render::curveReport(g.curves).largestRadiusWithoutOverlap(), o.radius,
                            1e-6 * o.radius);
                EXPECT_EQ(g.curves.pointCount(), readCurves(file).pointCount());
                EXPECT_EQ(g.scene.yarns.at(0).curves, "yarns.bcc");
                double nearest = std::numeric_limits<double>::infinity();
                for (const Curve& c : g.curves.curves)
                    for (const Vec3& p : c.points)
                        for (int k = 0; k < 8; ++k) {
                            const Vec3 corner =
                                p + o.radius * Vec3{k & 1 ? 1.0 : -1.0, k & 2 ? 1.0 : -1.0,
                                                    k & 4 ? 1.0 : -1.0};
                            const FilmPoint fp = project(g.scene.camera, w, h, corner);
                            ASSERT_GT(fp.depth, 0);
                            ASSERT_GE(fp.px, 0);
                            ASSERT_LE(fp.px, w);
                            ASSERT_GE(fp.py, 0);
                            ASSERT_LE(fp.py, h);
                            nearest = std::min({nearest, fp.px, w - fp.px, fp.py, h - fp.py});
                        }
                // Not lost in the frame: near the framed margin on the closer side
                // (the padded box, whose corners the cloth need not reach, is what
                // touches it).
                EXPECT_LT(nearest, (0.5 * (1 - kCurvesFill) + 0.05) * std::min(w, h));
                expectProjectionMatchesCamera(g);
            }
    }
}

// The radius: given in the file's units; 1 % of the box without any contact;
// refused with the reason when the curves touch, naming a closed curve's
// long closing segment.
TEST_F(SceneGenFiles, CurveRadiusIsGivenOrMeasuredOrRefusedWithTheReason) {
    const std::string straight = path("straight.txt");
    writeFileAtomic(straight, "0 0 0\n10 0 0\n");
    SceneOptions o = options();
    o.curves = straight;
    GeneratedScene g = curvesScene(o);
    EXPECT_EQ(g.curveRadiusSource, "one_percent_of_the_box");
    EXPECT_NEAR(g.curveRadius, 0.1, 1e-12);
    o.curveRadius = 0.5;
    g = curvesScene(o);
    EXPECT_EQ(g.curveRadiusSource, "given");
    EXPECT_NEAR(g.curveScale, 0.02, 1e-15);
    EXPECT_NEAR(length(g.curves.curves[0].points[1]), 0.2, 1e-12);
    // Curve 1 runs along y = -5 and up x = 10 in unit steps, and is closed:
    // its closing segment, (10, 5) back to (0, -5), crosses curve 0 at (5, 0).
    std::string text = "0 0 0\n8 0 0\n\n# closed\n";
    for (int x = 0; x <= 10; ++x) text += std::to_string(x) + " -5 0\n";
    for (int y = -4; y <= 5; ++y) text += "10 " + std::to_string(y) + " 0\n";
    writeFileAtomic(path("crossing.txt"), text);
    o.curves = path("crossing.txt");
    o.curveRadius.reset();
    expectInputError([&] { curvesScene(o); },
                     {"crossing.txt", "curves 0 and 1 touch or cross", "curve 1 is closed",
                      "closing segment", "spans 14.1", "--radius"});
}

}  // namespace
}  // namespace weft::eval
