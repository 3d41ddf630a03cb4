#include "weft/render/scene_file.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <map>
#include <nlohmann/json.hpp>
#include <utility>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/hash.h"
#include "weft/core/json_file.h"
#include "weft/core/json_message.h"
#include "weft/core/json_reader.h"
#include "weft/core/math.h"
#include "weft/core/text_parse.h"
#include "weft/render/scene_reader.h"
#include "weft/render/yarn_mode.h"

namespace weft::render {

namespace {

using nlohmann::json;

constexpr int kMaxFilmSide = 16384;
constexpr int kMaxSpp = 1 << 20;
constexpr int kMaxDepth = 10000;
constexpr int kMaxPlies = 16;
constexpr double kMaxPlyTwist = 100;
// up counts as parallel to the view direction below this sine of their angle:
// the camera frame built from cross(dir, up) would be numerically meaningless.
constexpr double kMinUpSine = 1e-6;

CameraDesc readCamera(const JsonObjectReader& scene) {
    const JsonObjectReader r = scene.object("camera", {"from", "to", "up", "fov_deg"});
    CameraDesc c;
    c.from = readSceneVec3(r, "from");
    c.to = readSceneVec3(r, "to");
    if (r.has("up")) c.up = readSceneVec3(r, "up");
    if (r.has("fov_deg")) c.fovDeg = r.number("fov_deg", NumberRange::open(0, 180));

    const auto vectorText = [](const Vec3& v) {
        // Appended piecewise: GCC 12 warns falsely (-Wrestrict) on "[" + string.
        std::string out = "[";
        out.append(formatNumber(v.x)).append(", ").append(formatNumber(v.y));
        return out.append(", ").append(formatNumber(v.z)).append("]");
    };
    const Vec3 view = c.to - c.from;
    if (c.from == c.to)
        r.failOutOfRange("to", vectorText(c.to), "any point other than camera.from");
    // From and to (within kMaxSceneCoordinate) may be a sub-normal distance
    // apart; up may be tiny.
    const Vec3 d = normalizeAnyLength(view);
    if (c.up == Vec3{0, 0, 0} || length(cross(d, normalizeAnyLength(c.up))) < kMinUpSine)
        r.failOutOfRange("up", vectorText(c.up),
                         "any vector not parallel to camera.to - camera.from");
    return c;
}

FilmDesc readFilm(const JsonObjectReader& scene) {
    const JsonObjectReader r = scene.object("film", {"width", "height"});
    FilmDesc f;
    if (r.has("width")) f.width = static_cast<int>(r.integer("width", {1, kMaxFilmSide}));
    if (r.has("height")) f.height = static_cast<int>(r.integer("height", {1, kMaxFilmSide}));
    return f;
}

RenderDesc readRender(const JsonObjectReader& scene) {
    const JsonObjectReader r =
        scene.object("render", {"spp", "max_depth", "seed", "sampler", "fiber_seed"});
    RenderDesc d;
    if (r.has("spp")) d.spp = static_cast<int>(r.integer("spp", {1, kMaxSpp}));
    if (r.has("max_depth")) d.maxDepth = static_cast<int>(r.integer("max_depth", {1, kMaxDepth}));
    if (r.has("seed")) d.seed = r.unsignedInteger("seed");
    if (r.has("fiber_seed")) d.fiberSeed = r.unsignedInteger("fiber_seed");
    static_assert(kSamplerKinds.size() == 2, "name every sampler kind below");
    if (r.has("sampler"))
        d.sampler = kSamplerKinds[r.oneOf(
            "sampler", {samplerKindName(kSamplerKinds[0]), samplerKindName(kSamplerKinds[1])})];
    return d;
}

// "appearance": [r, g, b] in [0, 1] or "#rrggbb", both sRGB-encoded.
Rgb readAppearance(const JsonObjectReader& r) {
    const json& v = r.value("appearance");
    if (!v.is_string()) {
        const std::vector<double> c =
            r.numbers("appearance", 3, NumberRange::closed(0, 1), "(r, g, b), sRGB");
        return Rgb(c[0], c[1], c[2]);
    }
    const std::optional<Rgb> hex = parseHexColour(v.get<std::string>());
    if (!hex)
        r.fail("appearance", "expected an sRGB colour, [r, g, b] in [0, 1] or \"#rrggbb\", got " +
                                 describeJson(v));
    return *hex;
}

YarnDesc readYarn(JsonObjectReader r, const std::string& baseDir) {
    r.allowKeys({"curves", "scale", "radius", "plies", "ply_twist", "model", "yarn", "colour",
                 "appearance", "vertex_colours", "mode"});
    YarnDesc y;
    y.curves = readFileName(r, "curves", baseDir, {".bcc", ".txt", ".obj"});
    y.model = readFileName(r, "model", baseDir, {});
    if (r.has("yarn")) y.yarn = YarnPoint::fromJson(r.value("yarn"), r.source(), r.pathOf("yarn"));
    if (r.has("scale")) y.scale = r.number("scale", sceneLengthRange());
    if (r.has("radius")) y.radius = r.number("radius", sceneLengthRange());
    if (r.has("plies")) y.plies = static_cast<int>(r.integer("plies", {1, kMaxPlies}));
    if (r.has("ply_twist"))
        y.plyTwist = r.number("ply_twist", NumberRange::closed(-kMaxPlyTwist, kMaxPlyTwist));
    if (r.has("colour")) {
        const std::vector<double> c = r.numbers("colour", 3, NumberRange::closed(0, 1), "(r, g, b)");
        y.colour = Rgb(c[0], c[1], c[2]);
    }
    if (r.has("appearance")) {
        if (y.colour)
            r.fail("appearance",
                   "give a yarn either \"colour\" (the fiber's C_TT) or \"appearance\" (the "
                   "colour it should look), not both");
        y.appearance = readAppearance(r);
    }
    if (r.has("vertex_colours")) {
        if (y.appearance)
            r.fail("vertex_colours",
                   "give a yarn either \"appearance\" (one colour) or \"vertex_colours\" (a "
                   "C_TT per curve point), not both");
        if (y.colour)
            r.fail("vertex_colours",
                   "give a yarn either \"colour\" (one colour) or \"vertex_colours\" (a colour "
                   "per curve point), not both");
        y.vertexColours = readFileName(r, "vertex_colours", baseDir, {".txt", ".npy"});
    }
    if (r.has("mode")) y.mode = readYarnModeName(r, "mode");
    return y;
}

}  // namespace

SceneDesc parseScene(const json& j, const std::string& pathForErrors, const std::string& baseDir) {
    JsonObjectReader r(j, pathForErrors.empty() ? "scene" : pathForErrors, "",
                       JsonIntegers::WholeNumbers);
    r.allowKeys(
        {"camera", "film", "render", "light_sampler", "lights", "yarns", "objects", "animation"});
    SceneDesc s;
    s.path = pathForErrors;
    s.baseDir = baseDir;
    s.camera = readCamera(r);
    if (r.has("film")) s.film = readFilm(r);
    if (r.has("render")) s.render = readRender(r);
    if (r.has("lights"))
        for (JsonObjectReader& light : r.objects("lights"))
            s.lights.push_back(readLight(std::move(light), baseDir));
    if (r.has("light_sampler")) s.lightSampler = LightSamplerDesc::read(r, s.lights.size());
    if (r.has("yarns"))
        for (JsonObjectReader& yarn : r.objects("yarns"))
            s.yarns.push_back(readYarn(std::move(yarn), baseDir));
    if (r.has("objects"))
        for (JsonObjectReader& object : r.objects("objects"))
            s.objects.push_back(readObject(std::move(object), baseDir));
    if (r.has("animation")) {
        const JsonObjectReader a = r.object("animation", {"frames", "turntable_deg"});
        if (a.has("frames")) {
            const std::vector<int64_t> f = a.integers("frames", 2, 2, {0, kMaxFrame});
            if (f[1] < f[0])
                a.failOutOfRange("frames",
                                 "[" + std::to_string(f[0]) + ", " + std::to_string(f[1]) + "]",
                                 "[first, last] with first <= last");
            s.animation.first = static_cast<int>(f[0]);
            s.animation.last = static_cast<int>(f[1]);
        }
        if (a.has("turntable_deg"))
            s.animation.turntableDeg = a.number("turntable_deg", NumberRange::closed(-3600, 3600));
    }
    // Every pattern must be well formed (checked now, not at the first frame).
    for (size_t i = 0; i < s.yarns.size(); ++i) {
        frameFileName(s.yarns[i].curves, 0, jsonIndexPath("yarns", i) + ".curves");
        frameFileName(s.yarns[i].vertexColours, 0, jsonIndexPath("yarns", i) + ".vertex_colours");
    }
    for (size_t i = 0; i < s.objects.size(); ++i)
        frameFileName(s.objects[i].file, 0, jsonIndexPath("objects", i) + ".file");
    return s;
}

SceneDesc parseSceneText(std::string_view text, const std::string& pathForErrors,
                         const std::string& baseDir) {
    return parseScene(parseJsonText(text, pathForErrors.empty() ? "scene" : pathForErrors),
                      pathForErrors, baseDir);
}

SceneDesc loadScene(const std::string& path) {
    const std::string text = readFile(path);
    // An absolute folder, so that the resolved paths (and toJson) do not
    // depend on the working directory of whoever reads them later.
    std::error_code ec;
    std::filesystem::path absolute = std::filesystem::absolute(path, ec);
    if (ec) absolute = path;
    return parseSceneText(text, path, absolute.parent_path().string());
}

json toJson(const SceneDesc& scene) {
    json j = json::object();
    const CameraDesc& c = scene.camera;
    j["camera"] = {{"from", vecJson(c.from)},
                   {"to", vecJson(c.to)},
                   {"up", vecJson(c.up)},
                   {"fov_deg", c.fovDeg}};
    j["film"] = {{"width", scene.film.width}, {"height", scene.film.height}};
    j["render"] = {{"spp", scene.render.spp},
                   {"max_depth", scene.render.maxDepth},
                   {"seed", scene.render.seed},
                   {"sampler", samplerKindName(scene.render.sampler)}};
    // Written only when not 0, so that a scene without one keeps its hash.
    if (scene.render.fiberSeed != 0) j["render"]["fiber_seed"] = scene.render.fiberSeed;
    json lights = json::array();
    for (const auto& light : scene.lights) lights.push_back(render::toJson(*light));
    j["lights"] = std::move(lights);
    // Written only when not uniform, so that a scene without one keeps its hash.
    if (!scene.lightSampler.isDefault()) j["light_sampler"] = scene.lightSampler.toJson();
    json yarns = json::array();
    for (const YarnDesc& y : scene.yarns) {
        json yj = {{"curves", y.curves},
                   {"scale", y.scale},
                   {"plies", y.plies},
                   {"ply_twist", y.plyTwist},
                   {"model", y.model}};
        if (y.radius) yj["radius"] = *y.radius;
        if (y.yarn) yj["yarn"] = y.yarn->toJson();
        if (y.colour) yj["colour"] = rgbJson(*y.colour);
        if (y.appearance) yj["appearance"] = rgbJson(*y.appearance);
        if (!y.vertexColours.empty()) yj["vertex_colours"] = y.vertexColours;
        // Written only when given, so that a scene without modes keeps its hash.
        if (!y.mode.empty()) yj["mode"] = y.mode;
        yarns.push_back(std::move(yj));
    }
    j["yarns"] = std::move(yarns);
    if (scene.animation.hasRange() || scene.animation.turntableDeg != 0) {
        json a = {{"turntable_deg", scene.animation.turntableDeg}};
        if (scene.animation.hasRange()) a["frames"] = {scene.animation.first, scene.animation.last};
        j["animation"] = std::move(a);
    }
    // Written only when there are some, so that a scene without keeps its hash.
    if (!scene.objects.empty()) {
        json objects = json::array();
        for (const ObjectDesc& o : scene.objects) objects.push_back(render::toJson(o));
        j["objects"] = std::move(objects);
    }
    return j;
}

namespace {

// The position and width of a name's frame pattern ("%d": width 0), or npos.
struct FramePattern {
    size_t at = std::string::npos, length = 0;
    int width = 0;
};
FramePattern findFramePattern(const std::string& name, const std::string& what) {
    FramePattern p;
    for (size_t i = 0; i < name.size(); ++i) {
        if (name[i] != '%') continue;
        size_t k = i + 1;
        int width = 0;
        if (k + 1 < name.size() && name[k] == '0' && name[k + 1] >= '1' && name[k + 1] <= '9')
            width = name[k + 1] - '0', k += 2;
        if (k >= name.size() || name[k] != 'd')
            throw InputError(what + ": \"" + name +
                             "\" has a '%' that is not a frame pattern (%d or %0Nd, N in [1, 9])");
        if (p.at != std::string::npos)
            throw InputError(what + ": \"" + name + "\" has more than one frame pattern");
        p = {i, k + 1 - i, width};
        i = k;
    }
    return p;
}

}  // namespace

bool hasFramePattern(const std::string& name) {
    return findFramePattern(name, "file").at != std::string::npos;
}

std::string frameFileName(const std::string& pattern, int frame, const std::string& what) {
    const FramePattern p = findFramePattern(pattern, what);
    if (p.at == std::string::npos) return pattern;
    std::string number = std::to_string(frame);
    if (static_cast<int>(number.size()) < p.width)
        number.insert(0, static_cast<size_t>(p.width) - number.size(), '0');
    return pattern.substr(0, p.at) + number + pattern.substr(p.at + p.length);
}

bool isAnimated(const SceneDesc& scene) {
    for (const YarnDesc& y : scene.yarns)
        if (hasFramePattern(y.curves) || hasFramePattern(y.vertexColours)) return true;
    for (const ObjectDesc& o : scene.objects)
        if (hasFramePattern(o.file)) return true;
    return false;
}

SceneDesc sceneAtFrame(const SceneDesc& scene, int frame, int first, int last) {
    SceneDesc s = scene;
    for (size_t i = 0; i < s.yarns.size(); ++i) {
        s.yarns[i].curves = frameFileName(s.yarns[i].curves, frame, "curves");
        s.yarns[i].vertexColours = frameFileName(s.yarns[i].vertexColours, frame, "vertex_colours");
    }
    for (ObjectDesc& o : s.objects) o.file = frameFileName(o.file, frame, "file");
    if (scene.animation.turntableDeg != 0) {
        const double angle = radians(scene.animation.turntableDeg) * (frame - first) /
                             static_cast<double>(last - first + 1);
        const double c = std::cos(angle), sn = std::sin(angle);
        const Vec3 d = s.camera.from - s.camera.to;
        s.camera.from = s.camera.to + Vec3{c * d.x + sn * d.z, d.y, -sn * d.x + c * d.z};
        const Vec3 u = s.camera.up;
        s.camera.up = {c * u.x + sn * u.z, u.y, -sn * u.x + c * u.z};
    }
    return s;
}

std::vector<CommandPath> sceneInputs(const SceneDesc& scene, const std::string& scenePath) {
    std::vector<CommandPath> inputs;
    if (!scenePath.empty()) inputs.push_back({"the scene file", scenePath});
    for (size_t i = 0; i < scene.lights.size(); ++i)
        for (const auto& [key, file] : scene.lights[i]->files())
            inputs.push_back({"the scene's lights[" + std::to_string(i) + "]." + key, file});
    for (size_t i = 0; i < scene.yarns.size(); ++i) {
        const std::string yarn = "the scene's yarns[" + std::to_string(i) + "].";
        inputs.push_back({yarn + "curves", scene.yarns[i].curves});
        inputs.push_back({yarn + "model", scene.yarns[i].model});
        if (!scene.yarns[i].vertexColours.empty())
            inputs.push_back({yarn + "vertex_colours", scene.yarns[i].vertexColours});
    }
    for (size_t i = 0; i < scene.objects.size(); ++i)
        if (!scene.objects[i].file.empty())
            inputs.push_back(
                {"the scene's objects[" + std::to_string(i) + "].file", scene.objects[i].file});
    return inputs;
}

std::string sceneHash(const SceneDesc& scene) {
    json j = toJson(scene);
    const std::string source = scene.path.empty() ? "scene" : scene.path;
    // A file referenced twice (one model for many yarns) is read once.
    std::map<std::string, std::string> digests;
    const auto digest = [&](json& value, const std::string& jsonPath) {
        const std::string path = value.get<std::string>();
        auto it = digests.find(path);
        if (it == digests.end()) {
            std::string bytes;
            try {
                bytes = readFile(path);
            } catch (const InputError& e) {
                throw InputError(source + ": " + jsonPath + ": " + e.what());
            }
            // The contents, not the path: a scene folder copied elsewhere keeps its hash.
            it = digests
                     .emplace(path, "fnv1a64:" + hex16(fnv1a64(bytes)) + ":" +
                                        std::to_string(bytes.size()))
                     .first;
        }
        value = it->second;
    };
    for (size_t i = 0; i < scene.lights.size(); ++i)
        for (const auto& [key, file] : scene.lights[i]->files())
            digest(j["lights"][i][key], jsonIndexPath("lights", i) + "." + key);
    for (size_t i = 0; i < scene.yarns.size(); ++i) {
        digest(j["yarns"][i]["curves"], jsonIndexPath("yarns", i) + ".curves");
        digest(j["yarns"][i]["model"], jsonIndexPath("yarns", i) + ".model");
        if (!scene.yarns[i].vertexColours.empty())
            digest(j["yarns"][i]["vertex_colours"], jsonIndexPath("yarns", i) + ".vertex_colours");
    }
    for (size_t i = 0; i < scene.objects.size(); ++i)
        if (!scene.objects[i].file.empty())
            digest(j["objects"][i]["file"], jsonIndexPath("objects", i) + ".file");
    // Object keys dump sorted (std::map), so the text is canonical.
    return hex16(fnv1a64("weft scene hash 1\n" + j.dump()));
}

}  // namespace weft::render
