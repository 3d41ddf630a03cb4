#include "weft/eval/scene_gen.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "weft/core/curves.h"
#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/image.h"
#include "weft/core/json_message.h"
#include "weft/core/math.h"
#include "weft/render/camera.h"
#include "weft/render/curve_report.h"
#include "weft/render/environment_light.h"
#include "weft/render/scene.h"
#include "weft/render/sphere_light.h"
#include "weft/yarn/family_model.h"
#include "weft/yarn/yarn_appearance.h"
#include "weft/yarn/yarn_model.h"

namespace weft::eval {

namespace {

namespace fs = std::filesystem;

constexpr double kFovDeg = 30;
// --floor's side, in box diagonals of the cloth.
constexpr double kFloorSize = 20;
// Share of the film's half-width the close-up's framed length spans.
constexpr double kCloseupFill = 0.95;
// Close-up: yarn length in radii and samples along it.
constexpr double kCloseupLengthRadii = 8;
constexpr int kCloseupSamplesPerRadius = 8;
// What a generator makes for one margin: whole curves, or each curve as its
// first and last point only (extendEndsOutOfView's tries).
constexpr bool kEndsOnly = true, kWholeCurves = false;
// The sample after i on a curve of samples 0..last: every one, or the ends only.
int nextSample(int i, int last, bool endsOnly) { return endsOnly && i < last ? last : i + 1; }
// Lights, relative to the camera distance D from the framed box's centre: two
// spheres of radius kLightRadius * D at distance D, in the directions
// (+-0.6 right, +-0.6 up, 0.55 towards the camera): outside a 30-degree view.
constexpr double kLightRadius = 0.12;
constexpr double kLightSide = 0.6, kLightFront = 0.55;
constexpr Rgb kKeyRadiance{40, 38, 34};   // warm, top-right
constexpr Rgb kFillRadiance{14, 15, 17};  // cool, bottom-left

std::string rangeError(const std::string& flag, const std::string& value,
                       const std::string& allowed) {
    return flag + " " + value + " is out of range: allowed " + allowed;
}

void checkInt(const std::string& flag, int v, int lo, int hi) {
    if (v < lo || v > hi)
        throw InputError(rangeError(flag, std::to_string(v),
                                    "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]"));
}

void checkReal(const std::string& flag, double v, double lo, double hi) {
    if (!std::isfinite(v) || v < lo || v > hi)
        throw InputError(rangeError(flag, formatNumber(v),
                                    "[" + formatNumber(lo) + ", " + formatNumber(hi) + "]"));
}

std::string absolutePath(const std::string& path) {
    return fs::absolute(fs::path(path)).lexically_normal().string();
}

// The corners of `box` grown by `pad` on every side.
Bounds3 padded(Bounds3 box, double pad) {
    box.lo -= Vec3{pad, pad, pad};
    box.hi += Vec3{pad, pad, pad};
    return box;
}

Vec3 boxCentre(const Bounds3& box) { return 0.5 * (box.lo + box.hi); }

// Sky (or envmap) plus the key and fill spheres around the camera's view.
std::vector<std::shared_ptr<const render::LightDesc>> paperLights(
    const render::CameraDesc& camera, const std::string& envmap) {
    std::vector<std::shared_ptr<const render::LightDesc>> lights;
    if (envmap.empty()) {
        lights.push_back(std::make_shared<render::SkyLightDesc>());
    } else {
        auto env = std::make_shared<render::EnvmapLightDesc>();
        env->file = absolutePath(envmap);
        lights.push_back(env);
    }

    const Vec3 toCentre = camera.to - camera.from;
    const double distance = length(toCentre);
    const render::ViewAxes axes = render::viewAxes(toCentre, camera.up);
    const Vec3 &forward = axes.forward, &right = axes.right, &up = axes.up;
    const auto sphere = [&](double side, const Rgb& radiance) {
        return std::make_shared<render::SphereLightDesc>(
            camera.to +
                distance * normalize(side * kLightSide * (right + up) - kLightFront * forward),
            kLightRadius * distance, radiance);
    };
    lights.push_back(sphere(+1, kKeyRadiance));
    lights.push_back(sphere(-1, kFillRadiance));
    return lights;
}

// The generated curves with the colour group (0 or 1) of each: with two
// colours, group g has colour g; otherwise every curve has the one colour.
// anchor: per curve, the point where the course parameter is 0 (x = 0 for
// the close-up and the warp, y = 0 for the weft, t = 0 for a knit course),
// from which space-dyed colours are measured along the curve, so that the
// pattern does not move with the margin that hides the ends.
struct PatternedCurves {
    CurveSet set;
    std::vector<int> group;
    std::vector<size_t> anchor;
    int margin = 0;  // the extension that put every end out of view
};

// Space-dyed colours (--dye-length): along each curve, colour 0 for
// L = dyeLength R of arc length from the anchor, then colour 1 for L, and so
// on both ways; a point takes the colour of the stretch it lies in.
void spaceDye(CurveSet& set, const std::vector<size_t>& anchor, const SceneOptions& o,
              const std::vector<Rgb>& colours) {
    const double stretch = *o.dyeLength * o.radius;
    for (size_t c = 0; c < set.curves.size(); ++c) {
        Curve& curve = set.curves[c];
        std::vector<double> arc(curve.points.size(), 0.0);
        for (size_t i = 1; i < arc.size(); ++i)
            arc[i] = arc[i - 1] + length(curve.points[i] - curve.points[i - 1]);
        curve.colours.clear();
        for (size_t i = 0; i < arc.size(); ++i) {
            const auto k = static_cast<int64_t>(std::floor((arc[i] - arc[anchor[c]]) / stretch));
            curve.colours.push_back(colours[k % 2 == 0 ? 0 : 1]);
        }
    }
}

GeneratedScene assemble(PatternedCurves curves, const render::CameraDesc& camera,
                        const SceneOptions& o, const SceneColours& colours,
                        const std::string& extension = ".txt") {
    GeneratedScene g;
    g.endMargin = curves.margin;
    g.colourWarnings = colours.neuralWarnings;
    render::SceneDesc& s = g.scene;
    s.camera = camera;
    s.film = {o.width, o.height};
    s.render.spp = o.spp;
    s.lights = paperLights(s.camera, o.envmap);
    render::YarnDesc yarn;
    yarn.radius = o.radius;
    yarn.plies = o.plies;
    yarn.plyTwist = o.plyTwist;
    yarn.model = absolutePath(o.model);
    yarn.yarn = o.yarn;
    if (o.dyeLength) {
        // Space-dyed: one entry, a colour per curve point.
        spaceDye(curves.set, curves.anchor, o, colours.fiber);
        yarn.vertexColours = kVertexColourFile;
        yarn.curves = yarnCurveFile(0, 1, extension);
        s.yarns.push_back(yarn);
        g.entryOfCurve.assign(curves.set.curves.size(), 0);
        g.curves = std::move(curves.set);
        return g;
    }
    // One yarn entry per colour used, in the order of the colours (an unused
    // colour would be an empty curve file).
    const int groups = o.colourCount() == 2 ? 2 : 1;
    const auto groupOf = [&](size_t c) { return groups == 2 ? curves.group[c] : 0; };
    std::vector<int> entryOfGroup(groups, -1);
    for (size_t c = 0; c < curves.set.curves.size(); ++c) entryOfGroup[groupOf(c)] = 0;
    for (int group = 0; group < groups; ++group) {
        if (entryOfGroup[group] < 0) continue;
        entryOfGroup[group] = static_cast<int>(s.yarns.size());
        if (!o.colours.empty()) yarn.colour = o.colours[group];
        if (!o.appearances.empty()) yarn.appearance = o.appearances[group];
        s.yarns.push_back(yarn);
    }
    for (size_t c = 0; c < curves.set.curves.size(); ++c)
        g.entryOfCurve.push_back(entryOfGroup[groupOf(c)]);
    for (int e = 0; e < static_cast<int>(s.yarns.size()); ++e)
        s.yarns[e].curves = yarnCurveFile(e, static_cast<int>(s.yarns.size()), extension);
    g.curves = std::move(curves.set);
    return g;
}

// Stripe s (0, 1, 2, ...; negative below the first) of index i, and its colour group.
int stripeGroup(int i, int stripe) {
    const int s = i >= 0 ? i / stripe : -((-i - 1) / stripe) - 1;
    return s % 2 == 0 ? 0 : 1;
}

// The shortest extension of the yarns (curvesWithMargin(0, ...), (1, ...),
// ...) whose every end lies outside the view: a cut yarn end is drawn as a
// sphere cap in neural mode and as flat-cut, splaying fibers in fiber mode,
// so ends in view would be compared for a difference no model is meant to
// capture. Each margin is tried on the curves' ends alone
// (curvesWithMargin(margin, kEndsOnly): every curve as its first and last
// point, the same numbers as the full curve's), so a try costs one point per
// yarn end, not the whole patch; only the margin found is generated in full.
// checkFilmShape bounds the margin that the allowed films need below
// kMaxEndMargin.
template <class CurvesWithMargin>
PatternedCurves extendEndsOutOfView(const CurvesWithMargin& curvesWithMargin,
                                    const render::CameraDesc& camera, const SceneOptions& o) {
    for (int margin = 0; margin <= kMaxEndMargin; ++margin) {
        const PatternedCurves ends = curvesWithMargin(margin, kEndsOnly);
        const auto& set = ends.set.curves;
        const bool allOut = std::all_of(set.begin(), set.end(), [&](const auto& c) {
            return c.closed || (outOfView(camera, o.width, o.height, c.points.front(), o.radius) &&
                                outOfView(camera, o.width, o.height, c.points.back(), o.radius));
        });
        if (allOut) {
            PatternedCurves curves = curvesWithMargin(margin, kWholeCurves);
            curves.margin = margin;
            return curves;
        }
    }
    throw std::logic_error("scene generator: yarn ends still in view after the largest margin");
}

// The film shapes a kind can frame (scene_gen.h, kMaxFilmAspect).
void checkFilmShape(SceneKind kind, const SceneOptions& o) {
    const std::string film = "--width " + std::to_string(o.width) + " --height " +
                             std::to_string(o.height) + ": ";
    if (o.width > kMaxFilmAspect * o.height)
        throw InputError(film + "the film is " + formatNumber(static_cast<double>(o.width) / o.height) +
                         " times as wide as tall; allowed at most " +
                         formatNumber(kMaxFilmAspect) +
                         " (a wider view, over 175 degrees across, needs the yarns to run on "
                         "hundreds of radii past the frame to keep their ends out of view)");
    if (kind != SceneKind::Closeup && o.height > kMaxPatchFilmTallness * o.width)
        throw InputError(film + "the film is " + formatNumber(static_cast<double>(o.height) / o.width) +
                         " times as tall as wide; a " + sceneKindName(kind) +
                         " allows at most " + formatNumber(kMaxPatchFilmTallness) +
                         " (the patch is seen from 19 degrees above: from 10.7 times as tall "
                         "as wide the bottom of the view looks past the cloth, which then "
                         "cannot fill the frame)");
}

// scene.json, yarns.txt or yarns-N.txt (N = 1, 2, ...), or the same in .bcc,
// and colours.txt: what writeScene writes.
bool isGeneratedSceneFile(const std::string& name) {
    if (name == "scene.json" || name == "yarns.txt" || name == "yarns.bcc" ||
        name == kVertexColourFile)
        return true;
    const std::string prefix = "yarns-",
                      suffix = name.size() > 4 ? name.substr(name.size() - 4) : "";
    if (suffix != ".txt" && suffix != ".bcc") return false;
    if (name.size() <= prefix.size() + suffix.size() || name.rfind(prefix, 0) != 0) return false;
    const std::string digits =
        name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
    return std::all_of(digits.begin(), digits.end(),
                       [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
}

// Patches are seen from the front and a little above; the close-up less so.
const Vec3 kPatchForward = normalize(Vec3{0, -0.35, -1});
const Vec3 kCloseupForward = normalize(Vec3{0, -0.2, -1});

}  // namespace

const char* sceneKindName(SceneKind kind) {
    switch (kind) {
        case SceneKind::Closeup:
            return "closeup";
        case SceneKind::Weave:
            return "weave";
        case SceneKind::Knit:
            return "knit";
        case SceneKind::Curves:
            return "curves";
    }
    return "?";
}

SceneKind parseSceneKind(const std::string& name) {
    for (SceneKind k : {SceneKind::Closeup, SceneKind::Weave, SceneKind::Knit, SceneKind::Curves})
        if (name == sceneKindName(k)) return k;
    throw InputError("unknown scene kind " + jsonString(name) +
                     ": allowed closeup, weave, knit, curves");
}

const char* curvesViewName(CurvesView view) {
    switch (view) {
        case CurvesView::ThreeQuarter:
            return "three-quarter";
        case CurvesView::Front:
            return "front";
        case CurvesView::Top:
            return "top";
    }
    return "?";
}

CurvesView parseCurvesView(const std::string& name) {
    for (CurvesView v : {CurvesView::ThreeQuarter, CurvesView::Front, CurvesView::Top})
        if (name == curvesViewName(v)) return v;
    throw InputError("--view " + jsonString(name) +
                     " is not a view: allowed three-quarter, front, top");
}

SceneColours SceneOptions::validate() const {
    if (model.empty())
        throw InputError("--model is required: the MODEL.json written by `weft fit`");
    checkInt("--size", size, 1, kMaxPatchSize);
    checkReal("--radius", radius, kMinRadius, kMaxRadius);
    checkInt("--plies", plies, 1, 16);
    checkReal("--ply-twist", plyTwist, -100, 100);
    checkInt("--width", width, 1, 16384);
    checkInt("--height", height, 1, 16384);
    checkInt("--spp", spp, 1, 1 << 20);
    if (!colours.empty() && !appearances.empty())
        throw InputError(
            "--colours and --appearance: give one of them (fiber colours C_TT, or "
            "the colours the yarns should look), not both");
    for (const auto& [flag, list] :
         {std::pair{"--colours", &colours}, {"--appearance", &appearances}}) {
        if (list->size() > 2)
            throw InputError(std::string(flag) + " takes one or two R,G,B colours, got " +
                             std::to_string(list->size()));
        for (const Rgb& c : *list)
            for (int ch = 0; ch < 3; ++ch)
                if (!std::isfinite(c[ch]) || c[ch] < 0 || c[ch] > 1)
                    throw InputError(rangeError(flag, formatNumber(c[ch]), "[0, 1]"));
    }
    if (stripe) {
        checkInt("--stripe", *stripe, 1, kMaxPatchSize);
        if (colourCount() != 2) throw InputError("--stripe applies to two --colours only");
        if (dyeLength)
            throw InputError(
                "--stripe and --dye-length exclude each other (stripes of yarns, or "
                "colours along every yarn)");
    }
    if (dyeLength) {
        checkReal("--dye-length", *dyeLength, kMinDyeLength, kMaxDyeLength);
        if (colourCount() != 2)
            throw InputError("--dye-length needs two --colours (the yarn alternates between them)");
    }
    if (!envmap.empty()) {
        const std::string ext = lowercaseExtension(envmap);
        if (ext != ".exr" && ext != ".hdr")
            throw InputError("--envmap " + envmap +
                             ": expected an .exr or .hdr lat-long environment map");
        // Loaded as the renderer will load it: a truncated or corrupt map fails here.
        try {
            render::EnvironmentLight::load(envmap, 1.0, 0.0);
        } catch (const InputError& e) {
            throw InputError(std::string("--envmap: ") + e.what());
        }
    }
    // A family model's yarn (docs/family.md) is the model of the scene's yarns.
    ModelFile file;
    try {
        file = ModelFile::load(model);
    } catch (const InputError& e) {
        throw InputError(std::string("--model: ") + e.what());
    }
    const YarnModel loaded = file.forYarn(yarn, "--model", "--yarn", "with --yarn");
    if (!appearances.empty() && !loaded.colour)
        throw InputError("--appearance: " + model +
                         " is fitted for one colour; colour by appearance needs a colour model "
                         "(models/MATERIAL-colour.json, or weft fit --colour-range)");
    SceneColours resolved;
    if (!appearances.empty()) {
        // Each --appearance within the material's reach.
        const AppearanceTable table =
            loaded.appearance ? *loaded.appearance : computeAppearanceTable(loaded, model);
        for (const Rgb& srgb : appearances)
            resolved.fiber.push_back(table.cTTFor(srgbToLinear(srgb), "--appearance"));
        return resolved;
    }
    resolved.fiber = colours;
    if (colours.empty()) return resolved;
    const std::string render = "weft render in neural mode (the default) will refuse this scene; ";
    if (!loaded.colour) {
        resolved.neuralWarnings.push_back(
            "--colours: " + model + " is fitted for one colour: " + render +
            "use a colour model (models/MATERIAL-colour.json, weft fit --colour-range) or render "
            "with --mode fiber or dual");
        return resolved;
    }
    for (const Rgb& c : colours) try {
            loaded.forColour(c, "--colours");
        } catch (const InputError& e) {
            resolved.neuralWarnings.push_back(std::string(e.what()) + ": " + render +
                                              "or use --appearance");
        }
    return resolved;
}

WeaveGeometry weaveGeometry(double radius) {
    WeaveGeometry g;
    g.amplitude = radius * (1 + kWeaveClearance);
    g.spacing = kPi * std::sqrt(2.0) * g.amplitude;
    return g;
}

KnitGeometry knitGeometry(double radius) {
    KnitGeometry g;
    g.scale = radius / kKnitUnitRadius;
    return g;
}

Vec3 knitPoint(const KnitGeometry& g, int row, double t) {
    return g.scale * Vec3{t + g.roundness * std::sin(2 * t),
                          g.height * std::cos(t) + row * g.rowSpacing, g.depth * std::cos(2 * t)};
}

render::CameraDesc frameBox(const Bounds3& box, const Vec3& forward, double fovDeg, int width,
                            int height, double fill, const Vec3& up) {
    render::CameraDesc cam;
    cam.fovDeg = fovDeg;
    cam.up = up;
    const render::ViewAxes axes = render::viewAxes(forward, cam.up);
    const render::FilmExtent film = render::filmExtent(fovDeg, width, height);
    const Vec3 &f = axes.forward, &r = axes.right, &u = axes.up;
    const double halfW = fill * film.halfWidth, halfH = fill * film.halfHeight;
    const Vec3 c = boxCentre(box);
    const double extent = length(box.hi - box.lo);
    // A corner q (relative to c) is at depth D + q.f from the camera at c - D f;
    // it is in view when |q.r| <= halfW (D + q.f) and |q.u| <= halfH (D + q.f).
    double distance = 1e-6 * extent;
    for (int i = 0; i < 8; ++i) {
        const Vec3 p{(i & 1) ? box.hi.x : box.lo.x, (i & 2) ? box.hi.y : box.lo.y,
                     (i & 4) ? box.hi.z : box.lo.z};
        const Vec3 q = p - c;
        const double depth = dot(q, f);
        distance = std::max({distance, std::abs(dot(q, r)) / halfW - depth,
                             std::abs(dot(q, u)) / halfH - depth, 1e-6 * extent - depth});
    }
    cam.to = c;
    cam.from = c - distance * f;
    return cam;
}

bool outOfView(const render::CameraDesc& camera, int width, int height, const Vec3& p,
               double radius) {
    const render::ViewAxes axes = render::viewAxes(camera.to - camera.from, camera.up);
    const render::FilmExtent film = render::filmExtent(camera.fovDeg, width, height);
    const Vec3 &f = axes.forward, &r = axes.right, &u = axes.up;
    const double halfW = film.halfWidth, halfH = film.halfHeight;
    // Every corner of the cube p +- radius beyond one and the same side of the
    // view frustum (its four side planes and the camera plane): then the whole
    // ball of radius `radius` around p is out of view.
    int beyond[5] = {0, 0, 0, 0, 0};
    for (int i = 0; i < 8; ++i) {
        const Vec3 corner =
            p + radius * Vec3{(i & 1) ? 1.0 : -1.0, (i & 2) ? 1.0 : -1.0, (i & 4) ? 1.0 : -1.0};
        const Vec3 q = corner - camera.from;
        const double depth = dot(q, f), x = dot(q, r), y = dot(q, u);
        beyond[0] += x > halfW * depth;
        beyond[1] += x < -halfW * depth;
        beyond[2] += y > halfH * depth;
        beyond[3] += y < -halfH * depth;
        beyond[4] += depth <= 0;
    }
    return std::any_of(std::begin(beyond), std::end(beyond), [](int n) { return n == 8; });
}

render::CameraDesc frameCover(double x0, double x1, double y0, double y1, const Vec3& forward,
                              double fovDeg, int width, int height) {
    render::CameraDesc cam;
    cam.fovDeg = fovDeg;
    const render::ViewAxes axes = render::viewAxes(forward, cam.up);
    const render::FilmExtent film = render::filmExtent(fovDeg, width, height);
    const Vec3 &f = axes.forward, &r = axes.right, &u = axes.up;
    const double halfW = film.halfWidth, halfH = film.halfHeight;
    const Vec3 c{0.5 * (x0 + x1), 0.5 * (y0 + y1), 0};
    // The footprint of the film on the plane grows with the distance D: find
    // the largest D at which the four corner rays land inside the rectangle.
    const auto covered = [&](double distance) {
        const Vec3 from = c - distance * f;
        for (const double sx : {-1.0, 1.0})
            for (const double sy : {-1.0, 1.0}) {
                const Vec3 dir = f + sx * halfW * r + sy * halfH * u;
                if (dir.z >= 0) return false;
                const Vec3 hit = from + (-from.z / dir.z) * dir;
                if (hit.x < x0 || hit.x > x1 || hit.y < y0 || hit.y > y1) return false;
            }
        return true;
    };
    const double extent = std::hypot(x1 - x0, y1 - y0);
    double lo = 0, hi = extent;
    while (covered(hi)) hi *= 2;  // terminates: the footprint outgrows the rectangle
    for (int i = 0; i < 60; ++i) {
        const double mid = 0.5 * (lo + hi);
        (covered(mid) ? lo : hi) = mid;
    }
    cam.to = c;
    cam.from = c - lo * f;
    return cam;
}

GeneratedScene closeupScene(const SceneOptions& o) {
    const SceneColours colours = o.validate();
    checkFilmShape(SceneKind::Closeup, o);
    if (o.colourCount() == 2 && !o.dyeLength)
        throw InputError(
            "--colours: a close-up is one yarn, so it takes one colour, or two "
            "with --dye-length (a space-dyed yarn)");
    // A yarn of length L along x, bowed up in y by 0.08 L and tilted in depth
    // by +-0.04 L: gently curved, seen from the front. The camera frames this
    // length; the yarn then runs on past both sides of the film.
    const double len = kCloseupLengthRadii * o.radius;
    const auto yarn = [&](int margin, bool endsOnly) {
        const int steps = static_cast<int>(kCloseupLengthRadii) * kCloseupSamplesPerRadius +
                          2 * margin * kCloseupSamplesPerRadius;
        Curve c;
        for (int i = 0; i <= steps; i = nextSample(i, steps, endsOnly)) {
            const double x =
                -0.5 * len +
                o.radius * (static_cast<double>(i) / kCloseupSamplesPerRadius - margin);
            c.points.push_back(
                {x, 0.08 * len * std::cos(kPi * x / len), 0.04 * len * std::sin(kPi * x / len)});
        }
        PatternedCurves curves;
        curves.set.curves.push_back(std::move(c));
        curves.group.push_back(0);
        curves.anchor.push_back(static_cast<size_t>((kCloseupLengthRadii / 2 + margin) *
                                                    kCloseupSamplesPerRadius));  // x = 0
        return curves;
    };
    const render::CameraDesc camera =
        frameBox(padded(bounds(yarn(0, kWholeCurves).set), o.radius), kCloseupForward, kFovDeg, o.width, o.height,
                 kCloseupFill);
    return assemble(extendEndsOutOfView(yarn, camera, o), camera, o, colours);
}

GeneratedScene weaveScene(const SceneOptions& o) {
    const SceneColours colours = o.validate();
    checkFilmShape(SceneKind::Weave, o);
    const WeaveGeometry g = weaveGeometry(o.radius);
    const double d = g.spacing, a = g.amplitude, k = kPi / d;
    const int n = o.size;
    // The view covers the cells of N x N yarns; `margin` more yarns on each
    // side, each running `margin` + 1 spacings past the outermost ones.
    const auto weave = [&](int margin, bool endsOnly) {
        const int first = -margin, last = n - 1 + margin;
        const double start = (first - 1) * d, span = (last - first + 2) * d;
        const int samples = (last - first + 2) * kWeaveSamplesPerSpacing + 1;
        const auto along = [&](int i) { return start + span * i / (samples - 1); };
        const auto parity = [](int j) { return ((j % 2) + 2) % 2 ? -1.0 : 1.0; };
        // Warp blocks start with colour 0, weft blocks with colour 1 (a check).
        PatternedCurves curves;
        for (int j = first; j <= last; ++j) {  // warp: along x at y = j d
            Curve c;
            for (int i = 0; i < samples; i = nextSample(i, samples - 1, endsOnly)) {
                const double x = along(i);
                c.points.push_back({x, j * d, parity(j) * a * std::cos(k * x)});
            }
            curves.set.curves.push_back(std::move(c));
            curves.group.push_back(stripeGroup(j, o.stripeWidth()));
            curves.anchor.push_back(static_cast<size_t>((1 - first) * kWeaveSamplesPerSpacing));
        }
        for (int i = first; i <= last; ++i) {  // weft: along y at x = i d, opposite phase
            Curve c;
            for (int s = 0; s < samples; s = nextSample(s, samples - 1, endsOnly)) {
                const double y = along(s);
                c.points.push_back({i * d, y, -parity(i) * a * std::cos(k * y)});
            }
            curves.set.curves.push_back(std::move(c));
            curves.group.push_back(1 - stripeGroup(i, o.stripeWidth()));
            curves.anchor.push_back(static_cast<size_t>((1 - first) * kWeaveSamplesPerSpacing));
        }
        return curves;
    };
    const double lo = -0.5 * d, hi = (n - 0.5) * d;
    const render::CameraDesc camera =
        frameCover(lo, hi, lo, hi, kPatchForward, kFovDeg, o.width, o.height);
    return assemble(extendEndsOutOfView(weave, camera, o), camera, o, colours);
}

GeneratedScene knitScene(const SceneOptions& o) {
    const SceneColours colours = o.validate();
    checkFilmShape(SceneKind::Knit, o);
    const KnitGeometry g = knitGeometry(o.radius);
    const int n = o.size;
    // The view covers N courses of N loops; `margin` + 1 more courses above
    // and below (the first one fills the top course's loops and the gaps below
    // the bottom one), and every course `margin` loops longer at both ends.
    const auto knit = [&](int margin, bool endsOnly) {
        const int loops = n + 2 * margin;
        const int samples = loops * kKnitSamplesPerLoop + 1;
        PatternedCurves curves;
        for (int row = -margin - 1; row <= n + margin; ++row) {
            Curve c;
            for (int i = 0; i < samples; i = nextSample(i, samples - 1, endsOnly))
                c.points.push_back(knitPoint(
                    g, row, kTwoPi * (static_cast<double>(i) / kKnitSamplesPerLoop - margin)));
            curves.set.curves.push_back(std::move(c));
            curves.group.push_back(stripeGroup(row, o.stripeWidth()));
            curves.anchor.push_back(static_cast<size_t>(margin * kKnitSamplesPerLoop));  // t = 0
        }
        return curves;
    };
    const double s = g.scale;
    const render::CameraDesc camera =
        frameCover(0, kTwoPi * n * s, -0.5 * g.rowSpacing * s, (n - 0.5) * g.rowSpacing * s,
                   kPatchForward, kFovDeg, o.width, o.height);
    return assemble(extendEndsOutOfView(knit, camera, o), camera, o, colours);
}

GeneratedScene curvesScene(const SceneOptions& o) {
    const SceneColours colours = o.validate();
    if (o.curves.empty())
        throw InputError("weft scene curves needs a curve file (.bcc, .txt, .obj)");
    if (o.curveRadius) checkReal("--radius", *o.curveRadius, 1e-300, 1e300);
    CurveSet set = readCurves(o.curves);
    double radius = 0;
    std::string from = "given";
    if (o.curveRadius) {
        radius = *o.curveRadius;
    } else {
        const render::CurveReport report = render::curveReport(set, std::nullopt, o.curves);
        radius = report.largestRadiusWithoutOverlap();
        from = "largest_without_overlap";
        const Bounds3 box = bounds(set);
        const double diagonal = length(box.hi - box.lo);
        if (std::isinf(radius)) {
            // No two points ever come close (one open curve, a plain circle):
            // a yarn as thick as 1 % of the cloth.
            radius = kNoContactRadiusFraction * diagonal;
            from = "one_percent_of_the_box";
        } else if (!(radius > 1e-9 * diagonal)) {
            throw InputError(o.curves + ": " + render::zeroRadiusExplanation(set, report) +
                             "; no yarn radius keeps them apart: give --radius in the file's "
                             "units (weft curves info " +
                             o.curves + " --radius R reports the overlap at R)");
        }
    }
    if (!(radius > 0) || !std::isfinite(radius))
        throw InputError(o.curves + ": no yarn radius could be chosen (the curves' box is empty)");
    const double scale = o.radius / radius;
    PatternedCurves curves;
    for (size_t c = 0; c < set.curves.size(); ++c) {
        Curve& curve = set.curves[c];
        for (Vec3& p : curve.points) p = scale * p;
        curve.radii.clear();
        curve.colours.clear();
        curves.group.push_back(
            o.colourCount() == 2 ? stripeGroup(static_cast<int>(c), o.stripeWidth()) : 0);
        curves.anchor.push_back(0);
    }
    curves.set = std::move(set);
    Vec3 forward{0, 0, -1}, up{0, 1, 0};
    if (o.view == CurvesView::Top) forward = {0, -1, 0}, up = {0, 0, -1};
    if (o.view == CurvesView::ThreeQuarter) {
        const double azimuth = radians(35.0), elevation = radians(30.0);
        forward = -Vec3{std::sin(azimuth) * std::cos(elevation), std::sin(elevation),
                        std::cos(azimuth) * std::cos(elevation)};
    }
    const render::CameraDesc camera = frameBox(padded(bounds(curves.set), o.radius), forward,
                                               kFovDeg, o.width, o.height, kCurvesFill, up);
    GeneratedScene g = assemble(std::move(curves), camera, o, colours, ".bcc");
    g.curveRadius = radius;
    g.curveScale = scale;
    g.curveRadiusSource = from;
    return g;
}

namespace {

// The --floor of a generated scene: under the cloth for the curves kind,
// behind the patch for the others (SceneOptions::floor).
void addFloor(GeneratedScene& g, SceneKind kind, const SceneOptions& o) {
    const Bounds3 box = padded(bounds(g.curves), o.radius);
    const Vec3 centre = boxCentre(box);
    render::ObjectDesc floor;
    floor.type = render::ObjectDesc::Type::Rectangle;
    const double side = kFloorSize * length(box.hi - box.lo);
    floor.size = {side, side};
    if (kind == SceneKind::Curves) {
        floor.normal = {0, 1, 0};
        floor.center = {centre.x, box.lo.y, centre.z};
    } else {
        floor.normal = {0, 0, 1};
        floor.center = {centre.x, centre.y, box.lo.z};
    }
    g.scene.objects.push_back(floor);
}

}  // namespace

GeneratedScene generateScene(SceneKind kind, const SceneOptions& options) {
    GeneratedScene g;
    switch (kind) {
        case SceneKind::Closeup:
            g = closeupScene(options);
            break;
        case SceneKind::Weave:
            g = weaveScene(options);
            break;
        case SceneKind::Knit:
            g = knitScene(options);
            break;
        case SceneKind::Curves:
            g = curvesScene(options);
            break;
    }
    if (options.floor) addFloor(g, kind, options);
    return g;
}

std::string yarnCurveFile(int entry, int entryCount, const std::string& extension) {
    return entryCount == 1 ? "yarns" + extension : "yarns-" + std::to_string(entry + 1) + extension;
}

std::vector<CurveSet> entryCurves(const GeneratedScene& generated) {
    std::vector<CurveSet> sets(generated.scene.yarns.size());
    for (size_t c = 0; c < generated.curves.curves.size(); ++c)
        sets.at(generated.entryOfCurve.at(c)).curves.push_back(generated.curves.curves[c]);
    return sets;
}

nlohmann::json sceneSummary(const GeneratedScene& generated, SceneKind kind, const std::string& dir,
                            std::vector<std::string>* warnings) {
    const fs::path folder(dir);
    std::vector<render::YarnEntryOverlap> overlap =
        render::checkYarnOverlap(generated.scene, entryCurves(generated));
    for (render::YarnEntryOverlap& entry : overlap) entry.curves = (folder / entry.curves).string();
    *warnings = render::yarnOverlapWarnings((folder / "scene.json").string(), overlap);
    nlohmann::json curveFiles = nlohmann::json::array(), colours = nlohmann::json::array(),
                   appearances = nlohmann::json::array(), colourFiles = nlohmann::json::array();
    for (const render::YarnDesc& yarn : generated.scene.yarns) {
        curveFiles.push_back((folder / yarn.curves).string());
        if (yarn.colour) colours.push_back({yarn.colour->r, yarn.colour->g, yarn.colour->b});
        if (yarn.appearance)
            appearances.push_back({yarn.appearance->r, yarn.appearance->g, yarn.appearance->b});
        if (!yarn.vertexColours.empty())
            colourFiles.push_back((folder / yarn.vertexColours).string());
    }
    nlohmann::json summary = {{"kind", sceneKindName(kind)},
                              {"scene", (folder / "scene.json").string()},
                              {"curves", curveFiles},
                              {"colours", colours},
                              {"appearances", appearances},
                              {"vertex_colours", colourFiles},
                              {"yarns", generated.curves.curves.size()},
                              {"points", generated.curves.pointCount()},
                              {"objects", generated.scene.objects.size()},
                              {"radius", *generated.scene.yarns.at(0).radius},
                              {"yarn_overlap", render::yarnOverlapJson(overlap)}};
    if (kind == SceneKind::Curves)
        summary["curve_file"] = {{"radius", generated.curveRadius},
                                 {"radius_from", generated.curveRadiusSource},
                                 {"scale", generated.curveScale}};
    return summary;
}

std::string vertexColoursText(const CurveSet& curves) {
    std::string text;
    char line[96];
    for (size_t c = 0; c < curves.curves.size(); ++c) {
        if (c > 0) text += "\n";
        for (const Rgb& colour : curves.curves[c].colours) {
            std::snprintf(line, sizeof line, "%.9g %.9g %.9g\n", colour.r, colour.g, colour.b);
            text += line;
        }
    }
    return text;
}

std::string curvesText(const CurveSet& curves) {
    // Points and closed flags: the colours have their own file.
    CurveSet out;
    for (const Curve& c : curves.curves)
        out.curves.push_back({c.points, {}, c.closed, CurveBasis::Polyline, {}});
    return formatCurveText(out, "yarns.txt");
}

void writeScene(const GeneratedScene& generated, const std::string& dir) {
    // The scene must read back (it names its curves relative to `dir`).
    const nlohmann::json json = render::toJson(generated.scene);
    render::parseScene(json, "scene.json", dir);

    std::error_code ec;
    if (fs::is_directory(fs::symlink_status(dir, ec))) {
        for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
            const std::string name = e.path().filename().string();
            if (!isGeneratedSceneFile(name))
                throw InputError("output directory '" + dir + "' exists and holds '" + name +
                                 "', which is not a file of a generated scene (scene.json, "
                                 "yarns.txt, yarns-N.txt, colours.txt): remove it or choose "
                                 "another directory");
        }
        if (ec) throw InputError("cannot list output directory '" + dir + "': " + ec.message());
    }
    TempDirCommit out(dir);
    const std::vector<CurveSet> sets = entryCurves(generated);
    for (size_t e = 0; e < sets.size(); ++e) {
        const render::YarnDesc& yarn = generated.scene.yarns[e];
        writeFileAtomic(out.path() + "/" + yarn.curves,
                        lowercaseExtension(yarn.curves) == ".bcc"
                            ? formatBcc(sets[e], "weft scene curves", yarn.curves)
                            : curvesText(sets[e]));
        if (!yarn.vertexColours.empty())
            writeFileAtomic(out.path() + "/" + yarn.vertexColours, vertexColoursText(sets[e]));
    }
    writeFileAtomic(out.path() + "/scene.json", json.dump(2) + "\n");
    out.commit();
}

}  // namespace weft::eval
