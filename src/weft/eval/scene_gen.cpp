#include "weft/eval/scene_gen.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "weft/core/curve_io.h"
#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/json_message.h"
#include "weft/core/math.h"
#include "weft/fit/yarn_model.h"

namespace weft::eval {

namespace {

namespace fs = std::filesystem;

constexpr double kFovDeg = 30;
// Share of the film's half-extents the framed box may fill: a close-up spans
// the frame, a patch keeps a small border.
constexpr double kCloseupFill = 0.95, kPatchFill = 0.92;
// Close-up: yarn length in radii and samples along it.
constexpr double kCloseupLengthRadii = 24;
constexpr int kCloseupSamples = 193;
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
render::Bounds3 padded(render::Bounds3 box, double pad) {
    box.lo -= Vec3{pad, pad, pad};
    box.hi += Vec3{pad, pad, pad};
    return box;
}

Vec3 boxCentre(const render::Bounds3& box) { return 0.5 * (box.lo + box.hi); }

// Sky (or envmap) plus the key and fill spheres around the camera's view.
std::vector<render::LightDesc> paperLights(const render::CameraDesc& camera,
                                           const std::string& envmap) {
    std::vector<render::LightDesc> lights;
    render::LightDesc env;
    if (envmap.empty()) {
        env.type = render::LightDesc::Type::Sky;
    } else {
        env.type = render::LightDesc::Type::Envmap;
        env.file = absolutePath(envmap);
    }
    lights.push_back(env);

    const Vec3 toCentre = camera.to - camera.from;
    const double distance = length(toCentre);
    const Vec3 forward = toCentre / distance;
    const Vec3 right = normalize(cross(forward, camera.up));
    const Vec3 up = cross(right, forward);
    const auto sphere = [&](double side, const Rgb& radiance) {
        render::LightDesc l;
        l.type = render::LightDesc::Type::Sphere;
        l.center = camera.to +
                   distance * normalize(side * kLightSide * (right + up) - kLightFront * forward);
        l.radius = kLightRadius * distance;
        l.radiance = radiance;
        return l;
    };
    lights.push_back(sphere(+1, kKeyRadiance));
    lights.push_back(sphere(-1, kFillRadiance));
    return lights;
}

GeneratedScene assemble(render::CurveSet curves, const SceneOptions& o, const Vec3& forward,
                        double fill) {
    GeneratedScene g;
    g.curves = std::move(curves);
    render::SceneDesc& s = g.scene;
    s.camera = frameBox(padded(render::bounds(g.curves), o.radius), forward, kFovDeg, o.width,
                        o.height, fill);
    s.film = {o.width, o.height};
    s.render.spp = o.spp;
    s.lights = paperLights(s.camera, o.envmap);
    render::YarnDesc yarn;
    yarn.curves = "yarns.txt";
    yarn.radius = o.radius;
    yarn.plies = o.plies;
    yarn.plyTwist = o.plyTwist;
    yarn.model = absolutePath(o.model);
    s.yarns.push_back(yarn);
    return g;
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
    }
    return "?";
}

SceneKind parseSceneKind(const std::string& name) {
    for (SceneKind k : {SceneKind::Closeup, SceneKind::Weave, SceneKind::Knit})
        if (name == sceneKindName(k)) return k;
    throw InputError("unknown scene kind " + jsonString(name) + ": allowed closeup, weave, knit");
}

void SceneOptions::validate() const {
    if (model.empty())
        throw InputError("--model is required: the MODEL.json written by `weft fit`");
    checkInt("--size", size, 1, kMaxPatchSize);
    checkReal("--radius", radius, kMinRadius, kMaxRadius);
    checkInt("--plies", plies, 1, 16);
    checkReal("--ply-twist", plyTwist, -100, 100);
    checkInt("--width", width, 1, 16384);
    checkInt("--height", height, 1, 16384);
    checkInt("--spp", spp, 1, 1 << 20);
    if (!envmap.empty()) {
        const std::string ext = lowercaseExtension(envmap);
        if (ext != ".exr" && ext != ".hdr")
            throw InputError("--envmap " + envmap +
                             ": expected an .exr or .hdr lat-long environment map");
        std::error_code ec;
        if (!fs::is_regular_file(envmap, ec) || ::access(envmap.c_str(), R_OK) != 0)
            throw InputError("--envmap " + envmap + ": not a readable file");
    }
    try {
        loadYarnModel(model);
    } catch (const InputError& e) {
        throw InputError(std::string("--model: ") + e.what());
    }
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

render::CameraDesc frameBox(const render::Bounds3& box, const Vec3& forward, double fovDeg,
                            int width, int height, double fill) {
    render::CameraDesc cam;
    cam.fovDeg = fovDeg;
    const Vec3 f = normalize(forward);
    const Vec3 r = normalize(cross(f, cam.up));
    const Vec3 u = cross(r, f);
    // The half-extents of the image plane at distance 1, as render::Camera.
    const double half = std::tan(0.5 * radians(fovDeg));
    const double aspect = static_cast<double>(width) / height;
    const double halfW = fill * (aspect >= 1 ? half * aspect : half);
    const double halfH = fill * (aspect >= 1 ? half : half / aspect);
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

GeneratedScene closeupScene(const SceneOptions& o) {
    o.validate();
    // A yarn of length L along x, bowed up in y by 0.08 L and tilted in depth
    // by +-0.04 L: gently curved, seen from the front.
    const double len = kCloseupLengthRadii * o.radius;
    render::Curve c;
    for (int i = 0; i < kCloseupSamples; ++i) {
        const double x = len * (static_cast<double>(i) / (kCloseupSamples - 1) - 0.5);
        c.points.push_back(
            {x, 0.08 * len * std::cos(kPi * x / len), 0.04 * len * std::sin(kPi * x / len)});
    }
    render::CurveSet set;
    set.curves.push_back(std::move(c));
    return assemble(std::move(set), o, kCloseupForward, kCloseupFill);
}

GeneratedScene weaveScene(const SceneOptions& o) {
    o.validate();
    const WeaveGeometry g = weaveGeometry(o.radius);
    const double d = g.spacing, a = g.amplitude, k = kPi / d;
    const int n = o.size;
    // Each yarn runs one spacing beyond the outermost crossing yarns: [-d, n d].
    const int samples = (n + 1) * kWeaveSamplesPerSpacing + 1;
    const auto along = [&](int i) { return -d + (n + 1) * d * i / (samples - 1); };
    render::CurveSet set;
    for (int j = 0; j < n; ++j) {  // warp: along x at y = j d
        const double sign = j % 2 ? -1 : 1;
        render::Curve c;
        for (int i = 0; i < samples; ++i) {
            const double x = along(i);
            c.points.push_back({x, j * d, sign * a * std::cos(k * x)});
        }
        set.curves.push_back(std::move(c));
    }
    for (int i = 0; i < n; ++i) {  // weft: along y at x = i d, opposite phase
        const double sign = i % 2 ? 1 : -1;
        render::Curve c;
        for (int s = 0; s < samples; ++s) {
            const double y = along(s);
            c.points.push_back({i * d, y, sign * a * std::cos(k * y)});
        }
        set.curves.push_back(std::move(c));
    }
    return assemble(std::move(set), o, kPatchForward, kPatchFill);
}

GeneratedScene knitScene(const SceneOptions& o) {
    o.validate();
    const KnitGeometry g = knitGeometry(o.radius);
    const int n = o.size;
    const int samples = n * kKnitSamplesPerLoop + 1;  // t in [0, 2 pi n]
    render::CurveSet set;
    for (int row = 0; row < n; ++row) {
        render::Curve c;
        for (int i = 0; i < samples; ++i)
            c.points.push_back(knitPoint(g, row, kTwoPi * i / kKnitSamplesPerLoop));
        set.curves.push_back(std::move(c));
    }
    return assemble(std::move(set), o, kPatchForward, kPatchFill);
}

GeneratedScene generateScene(SceneKind kind, const SceneOptions& options) {
    switch (kind) {
        case SceneKind::Closeup:
            return closeupScene(options);
        case SceneKind::Weave:
            return weaveScene(options);
        case SceneKind::Knit:
            return knitScene(options);
    }
    throw std::logic_error("unknown scene kind");
}

std::string curvesText(const render::CurveSet& curves) {
    CurveSet out;
    for (const render::Curve& c : curves.curves) {
        out.curves.push_back(c.points);
        out.closed.push_back(c.closed);
    }
    return formatCurveText(out);
}

void writeScene(const GeneratedScene& generated, const std::string& dir) {
    // The scene must read back (it names its curves relative to `dir`).
    const nlohmann::json json = render::toJson(generated.scene);
    render::parseScene(json, "scene.json", dir);

    std::error_code ec;
    if (fs::is_directory(fs::symlink_status(dir, ec))) {
        for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
            const std::string name = e.path().filename().string();
            if (name != "scene.json" && name != "yarns.txt")
                throw InputError("output directory '" + dir + "' exists and holds '" + name +
                                 "', which is not a file of a generated scene (scene.json, "
                                 "yarns.txt): remove it or choose another directory");
        }
        if (ec) throw InputError("cannot list output directory '" + dir + "': " + ec.message());
    }
    TempDirCommit out(dir);
    writeFileAtomic(out.path() + "/yarns.txt", curvesText(generated.curves));
    writeFileAtomic(out.path() + "/scene.json", json.dump(2) + "\n");
    out.commit();
}

}  // namespace weft::eval
