#include "weft/render/scene_file.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <typeinfo>
#include <utility>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/rng.h"
#include "weft/core/test_util.h"
#include "weft/render/constant_light.h"
#include "weft/render/delta_lights.h"
#include "weft/render/environment_light.h"
#include "weft/render/sphere_light.h"
#include "weft/render/yarn_mode.h"

namespace weft::render {
namespace {

using nlohmann::json;
using testing::expectInputError;
using SceneFileTest = testing::TempDirTest;

// Every key set, none to its default.
const std::string kFullScene = R"({
  "camera": {"from": [0, 1.5, 4], "to": [0, 0.5, 0], "up": [0, 1, 0.25], "fov_deg": 35},
  "film": {"width": 640, "height": 480},
  "render": {"spp": 256, "max_depth": 50, "seed": 7, "sampler": "sobol"},
  "lights": [
    {"type": "sky", "scale": 0.5},
    {"type": "envmap", "file": "maps/studio.exr", "scale": 2, "rotate_deg": -90},
    {"type": "sphere", "center": [1, 2, 3], "radius": 0.25, "radiance": [10, 9, 8]},
    {"type": "constant", "radiance": [0.1, 0.2, 0.3]},
    {"type": "point", "position": [-1, 3, 0.5], "intensity": [5, 6, 7]},
    {"type": "directional", "direction": [1, -2, 0], "irradiance": [2, 3, 4]}
  ],
  "yarns": [
    {"curves": "knit.bcc", "scale": 0.01, "radius": 0.02, "plies": 3, "ply_twist": -0.3,
     "model": "../models/fleece.json", "mode": "dual"},
    {"curves": "/abs/rib.OBJ", "model": "fleece.json"}
  ]
})";

const std::string kMinimalScene = R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0]}})";

// Replaces light i of s by a copy of it (of type T) changed by `edit`.
template <typename T, typename Edit>
void editLight(SceneDesc& s, size_t i, Edit edit) {
    auto light = std::make_shared<T>(s.lights[i]->as<T>());
    edit(*light);
    s.lights[i] = light;
}

// Names of the fields in which a and b differ (empty: the same scene).
std::vector<std::string> differences(const SceneDesc& a, const SceneDesc& b) {
    std::vector<std::string> d;
    const auto check = [&](bool same, const std::string& name) {
        if (!same) d.push_back(name);
    };
    check(a.path == b.path, "path");
    check(a.baseDir == b.baseDir, "baseDir");
    check(a.camera.from == b.camera.from, "camera.from");
    check(a.camera.to == b.camera.to, "camera.to");
    check(a.camera.up == b.camera.up, "camera.up");
    check(a.camera.fovDeg == b.camera.fovDeg, "camera.fov_deg");
    check(a.film.width == b.film.width, "film.width");
    check(a.film.height == b.film.height, "film.height");
    check(a.render.spp == b.render.spp, "render.spp");
    check(a.render.maxDepth == b.render.maxDepth, "render.max_depth");
    check(a.render.seed == b.render.seed, "render.seed");
    check(a.render.sampler == b.render.sampler, "render.sampler");
    check(a.render.fiberSeed == b.render.fiberSeed, "render.fiber_seed");
    check(a.lights.size() == b.lights.size(), "lights.size");
    for (size_t i = 0; i < std::min(a.lights.size(), b.lights.size()); ++i) {
        const LightDesc &x = *a.lights[i], &y = *b.lights[i];
        const std::string p = "lights[" + std::to_string(i) + "].";
        check(std::string(x.type()) == y.type(), p + "type");
        // Every key of the type, compared as the numbers and strings it holds.
        check(x.params() == y.params(), p + "params");
        check(x.files() == y.files(), p + "files");
    }
    check(a.yarns.size() == b.yarns.size(), "yarns.size");
    for (size_t i = 0; i < std::min(a.yarns.size(), b.yarns.size()); ++i) {
        const YarnDesc &x = a.yarns[i], &y = b.yarns[i];
        const std::string p = "yarns[" + std::to_string(i) + "].";
        check(x.curves == y.curves, p + "curves");
        check(x.scale == y.scale, p + "scale");
        check(x.radius == y.radius, p + "radius");
        check(x.plies == y.plies, p + "plies");
        check(x.plyTwist == y.plyTwist, p + "ply_twist");
        check(x.model == y.model, p + "model");
        check(x.mode == y.mode, p + "mode");
        check(x.colour == y.colour, p + "colour");
        check(x.appearance == y.appearance, p + "appearance");
    }
    return d;
}

std::string joined(const std::vector<std::string>& names) {
    std::string out;
    for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
    return out;
}

SceneDesc parseJson(const json& j) { return parseScene(j, "scene.json", "/data/scenes"); }

// The full scene with the value at `pointer` replaced (or added).
json fullWith(const std::string& pointer, const json& value) {
    json j = json::parse(kFullScene);
    j[json::json_pointer(pointer)] = value;
    return j;
}

// The full scene without the value at `pointer`.
json fullWithout(const std::string& pointer) {
    json j = json::parse(kFullScene);
    const json::json_pointer p(pointer);
    j[p.parent_pointer()].erase(p.back());
    return j;
}

void expectRejected(const json& j, std::initializer_list<std::string> parts) {
    expectInputError([&] { parseJson(j); }, parts);
    // The same through the text parser; NaN has no JSON text (dump writes
    // null, and NaN != NaN), so such a tree only has to be rejected.
    const std::string text = j.dump();
    const auto parse = [&] { parseSceneText(text, "scene.json", "/data/scenes"); };
    if (json::parse(text) == j)
        expectInputError(parse, parts);
    else
        expectInputError(parse, {"scene.json: "});
}

TEST(SceneFile, FullSceneParsesEveryKey) {
    const SceneDesc s = parseSceneText(kFullScene, "scenes/scene.json", "/data/scenes");
    EXPECT_EQ(s.path, "scenes/scene.json");
    EXPECT_EQ(s.baseDir, "/data/scenes");
    EXPECT_EQ(s.camera.from, Vec3(0, 1.5, 4));
    EXPECT_EQ(s.camera.to, Vec3(0, 0.5, 0));
    EXPECT_EQ(s.camera.up, Vec3(0, 1, 0.25));
    EXPECT_EQ(s.camera.fovDeg, 35);
    EXPECT_EQ(s.film.width, 640);
    EXPECT_EQ(s.film.height, 480);
    EXPECT_EQ(s.render.spp, 256);
    EXPECT_EQ(s.render.maxDepth, 50);
    EXPECT_EQ(s.render.seed, 7u);
    EXPECT_EQ(s.render.sampler, SamplerKind::Sobol);

    ASSERT_EQ(s.lights.size(), 6u);
    EXPECT_STREQ(s.lights[0]->type(), "sky");
    EXPECT_EQ(s.lights[0]->as<SkyLightDesc>().scale, 0.5);
    EXPECT_STREQ(s.lights[1]->type(), "envmap");
    const auto& envmap = s.lights[1]->as<EnvmapLightDesc>();
    EXPECT_EQ(envmap.file, "/data/scenes/maps/studio.exr");
    EXPECT_EQ(envmap.scale, 2);
    EXPECT_EQ(envmap.rotateDeg, -90);
    EXPECT_STREQ(s.lights[2]->type(), "sphere");
    const auto& sphere = s.lights[2]->as<SphereLightDesc>();
    EXPECT_EQ(sphere.center, Vec3(1, 2, 3));
    EXPECT_EQ(sphere.radius, 0.25);
    EXPECT_EQ(sphere.radiance, Rgb(10, 9, 8));
    EXPECT_STREQ(s.lights[3]->type(), "constant");
    EXPECT_EQ(s.lights[3]->as<ConstantLightDesc>().radiance, Rgb(0.1, 0.2, 0.3));
    EXPECT_THROW(s.lights[3]->as<SphereLightDesc>(), std::logic_error);
    const auto& point = s.lights[4]->as<PointLightDesc>();
    EXPECT_EQ(point.position, Vec3(-1, 3, 0.5));
    EXPECT_EQ(point.intensity, Rgb(5, 6, 7));
    const auto& directional = s.lights[5]->as<DirectionalLightDesc>();
    EXPECT_EQ(directional.direction, Vec3(1, -2, 0));  // as written, not normalized
    EXPECT_EQ(directional.irradiance, Rgb(2, 3, 4));

    ASSERT_EQ(s.yarns.size(), 2u);
    const YarnDesc& y = s.yarns[0];
    EXPECT_EQ(y.curves, "/data/scenes/knit.bcc");
    EXPECT_EQ(y.scale, 0.01);
    ASSERT_TRUE(y.radius.has_value());
    EXPECT_EQ(*y.radius, 0.02);
    EXPECT_EQ(y.plies, 3);
    EXPECT_EQ(y.plyTwist, -0.3);
    EXPECT_EQ(y.model, "/data/scenes/../models/fleece.json");
    EXPECT_EQ(y.mode, "dual");
    EXPECT_EQ(s.yarns[1].mode, "");  // absent: neural, and not written back
    // Absolute paths stay; the extension check ignores case.
    EXPECT_EQ(s.yarns[1].curves, "/abs/rib.OBJ");
    EXPECT_EQ(s.yarns[1].model, "/data/scenes/fleece.json");
}

// The registries (light.h, yarn_mode.h) are what the reader accepts: a new
// light type or drawing mode must appear in kFullScene, so that the round
// trip and the range checks below cover it.
TEST(SceneFile, EveryRegisteredLightTypeIsInTheFullScene) {
    const SceneDesc s = parseSceneText(kFullScene, "scene.json", "/data/scenes");
    std::vector<std::string> read;
    for (const auto& light : s.lights) read.push_back(light->type());
    std::vector<std::string> names;
    for (const LightType& type : lightTypes()) {
        names.push_back(type.name);
        EXPECT_NE(std::find(read.begin(), read.end(), type.name), read.end()) << type.name;
    }
    EXPECT_EQ(names, (std::vector<std::string>{"sky", "envmap", "sphere", "constant", "point",
                                               "directional"}));
    // Each description writes itself under its own type name.
    for (const auto& light : s.lights) EXPECT_EQ(toJson(*light).at("type"), light->type());
    // The modes the scene names are the registered ones.
    std::vector<std::string> modes;
    for (const YarnMode* mode : yarnModes()) modes.push_back(mode->name());
    EXPECT_EQ(modes, (std::vector<std::string>{"neural", "fiber", "dual"}));
    EXPECT_EQ(&yarnModeNamed("fiber"), yarnModes()[1]);
    expectInputError([] { yarnModeNamed("fibre", "--mode"); },
                     {"--mode \"fibre\" is not a render mode: allowed neural, fiber, dual"});
}

TEST(SceneFile, DefaultsFillEveryOptionalKey) {
    const SceneDesc s = parseSceneText(kMinimalScene, "", "");
    EXPECT_EQ(s.path, "");
    EXPECT_EQ(s.camera.from, Vec3(0, 0, 5));
    EXPECT_EQ(s.camera.to, Vec3(0, 0, 0));
    EXPECT_EQ(s.camera.up, Vec3(0, 1, 0));
    EXPECT_EQ(s.camera.fovDeg, 30);
    EXPECT_EQ(s.film.width, 512);
    EXPECT_EQ(s.film.height, 512);
    EXPECT_EQ(s.render.spp, 64);
    EXPECT_EQ(s.render.maxDepth, 1000);
    EXPECT_EQ(s.render.seed, 0u);
    EXPECT_EQ(s.render.sampler, SamplerKind::Independent);
    EXPECT_TRUE(s.lights.empty());  // the procedural sky
    EXPECT_TRUE(s.yarns.empty());

    const SceneDesc t = parseSceneText(R"({
        "camera": {"from": [0, 0, 5], "to": [0, 0, 0]}, "film": {}, "render": {},
        "lights": [{"type": "sky"}, {"type": "envmap", "file": "a.HDR"}],
        "yarns": [{"curves": "k.txt", "model": "m.json"}]})",
                                       "s.json", "");
    EXPECT_EQ(t.film.width, 512);
    EXPECT_EQ(t.render.spp, 64);
    ASSERT_EQ(t.lights.size(), 2u);
    EXPECT_EQ(t.lights[0]->as<SkyLightDesc>().scale, 1);
    const auto& envmap = t.lights[1]->as<EnvmapLightDesc>();
    EXPECT_EQ(envmap.file, "a.HDR");  // no base folder: the name as written
    EXPECT_EQ(envmap.scale, 1);
    EXPECT_EQ(envmap.rotateDeg, 0);
    ASSERT_EQ(t.yarns.size(), 1u);
    EXPECT_EQ(t.yarns[0].scale, 1);
    EXPECT_FALSE(t.yarns[0].radius.has_value());
    EXPECT_EQ(t.yarns[0].plies, 1);
    EXPECT_EQ(t.yarns[0].plyTwist, 0);
}

TEST(SceneFile, EveryMissingRequiredKeyIsNamed) {
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"/camera", "missing key \"camera\""},
        {"/camera/from", "camera: missing key \"from\""},
        {"/camera/to", "camera: missing key \"to\""},
        {"/lights/0/type", "lights[0]: missing key \"type\""},
        {"/lights/1/file", "lights[1]: missing key \"file\""},
        {"/lights/2/center", "lights[2]: missing key \"center\""},
        {"/lights/2/radius", "lights[2]: missing key \"radius\""},
        {"/lights/2/radiance", "lights[2]: missing key \"radiance\""},
        {"/lights/3/radiance", "lights[3]: missing key \"radiance\""},
        {"/lights/4/position", "lights[4]: missing key \"position\""},
        {"/lights/4/intensity", "lights[4]: missing key \"intensity\""},
        {"/lights/5/direction", "lights[5]: missing key \"direction\""},
        {"/lights/5/irradiance", "lights[5]: missing key \"irradiance\""},
        {"/yarns/0/curves", "yarns[0]: missing key \"curves\""},
        {"/yarns/1/model", "yarns[1]: missing key \"model\""},
    };
    for (const auto& [pointer, message] : cases) {
        SCOPED_TRACE(pointer);
        expectRejected(fullWithout(pointer), {"scene.json: " + message});
    }
    // Optional blocks may go.
    for (const char* block : {"/film", "/render", "/lights", "/yarns", "/camera/up"})
        EXPECT_NO_THROW(parseJson(fullWithout(block))) << block;
}

TEST(SceneFile, UnknownKeysAreNamedWithTheirPath) {
    expectInputError([] { parseJson(fullWith("/camera/fov", 30)); },
                     {"scene.json: camera: unknown key \"fov\" (allowed: from, to, up, "
                      "fov_deg)"});
    expectInputError([] { parseJson(fullWith("/cameras", json::object())); },
                     {"scene.json: unknown key \"cameras\" (allowed: camera, film, render, "
                      "light_sampler, lights, yarns, objects, animation)"});
    expectInputError([] { parseJson(fullWith("/film/depth", 8)); },
                     {"film: unknown key \"depth\" (allowed: width, height)"});
    expectInputError(
        [] { parseJson(fullWith("/render/samples", 8)); },
        {"render: unknown key \"samples\" (allowed: spp, max_depth, seed, sampler, fiber_seed)"});
    // Keys of another light type are unknown for this one.
    expectInputError([] { parseJson(fullWith("/lights/0/radius", 1)); },
                     {"lights[0]: unknown key \"radius\" (allowed: type, scale)"});
    expectInputError([] { parseJson(fullWith("/lights/3/scale", 1)); },
                     {"lights[3]: unknown key \"scale\" (allowed: type, radiance)"});
    expectInputError(
        [] {
            parseJson(fullWith("/lights/4/radiance", json::array({1, 1, 1})));
        },
        {"lights[4]: unknown key \"radiance\" (allowed: type, position, intensity)"});
    expectInputError([] { parseJson(fullWith("/lights/5/angle", 0.5)); },
                     {"lights[5]: unknown key \"angle\" (allowed: type, direction, irradiance)"});
    expectInputError(
        [] { parseJson(fullWith("/yarns/1/twist", 1)); },
        {"yarns[1]: unknown key \"twist\" (allowed: curves, scale, radius, plies, ply_twist, "
         "model, yarn, colour, appearance, vertex_colours, mode)"});
    // A scene parsed from memory without a name is called "scene".
    expectInputError([] { parseScene(fullWith("/film/depth", 8), "", ""); },
                     {"scene: film: unknown key \"depth\""});
    // A misspelt required key reads as the typo, not as a missing key.
    expectInputError(
        [] {
            parseJson(fullWith("/camera/From", json::array({1, 2, 3})));
        },
        {"camera: unknown key \"From\""});
}

struct RangeCase {
    std::string pointer;
    json bad;
    std::vector<std::string> message;
    json goodBoundary;  // null: no boundary to check
};

TEST(SceneFile, RangeAndTypeChecksNameThePathAndTheAllowedRange) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double inf = std::numeric_limits<double>::infinity();
    const std::vector<RangeCase> cases = {
        {"/camera/fov_deg", 180, {"camera.fov_deg = 180 is out of range: allowed (0, 180)"}, 179.9},
        {"/camera/fov_deg", 0, {"camera.fov_deg = 0 is out of range"}, 1e-6},
        {"/camera/fov_deg",
         "30",
         {"camera.fov_deg: expected a number in (0, 180), got the string \"30\""},
         nullptr},
        {"/camera/fov_deg",
         nan,
         {"camera.fov_deg: expected a finite number in (0, 180), got nan"},
         nullptr},
        {"/camera/from",
         json::array({0, 1}),
         {"camera.from: expected an array of 3 numbers in [-1e+06, 1e+06] scene units, got an "
          "array of 2"},
         nullptr},
        {"/camera/from",
         json::array({0, 1, inf}),
         {"camera.from[2]: expected a finite number in [-1e+06, 1e+06] scene units, got inf"},
         nullptr},
        {"/camera/up",
         json::array({0, true, 0}),
         {"camera.up[1]: expected a number in [-1e+06, 1e+06] scene units, got true"},
         nullptr},
        {"/camera", json::array(), {"camera: expected an object, got an array of 0"}, nullptr},
        {"/film/width", 0, {"film.width = 0 is out of range: allowed [1, 16384]"}, 1},
        {"/film/height", 16385, {"film.height = 16385 is out of range: allowed [1, 16384]"}, 16384},
        {"/film/width", 2.5, {"film.width: expected an integer in [1, 16384], got 2.5"}, 64.0},
        {"/render/spp", 0, {"render.spp = 0 is out of range: allowed [1, 1048576]"}, 1},
        {"/render/spp", 1048577, {"render.spp = 1048577 is out of range"}, 1048576},
        {"/render/spp", 2.5, {"render.spp: expected an integer in [1, 1048576], got 2.5"}, 1e3},
        {"/render/spp",
         uint64_t{1} << 63,
         {"render.spp = 9223372036854775808 is out of range"},
         nullptr},
        {"/render/max_depth",
         10001,
         {"render.max_depth = 10001 is out of range: allowed [1, "
          "10000]"},
         10000},
        {"/render/seed",
         -1,
         {"render.seed = -1 is out of range: allowed [0, "
          "18446744073709551615]"},
         std::numeric_limits<uint64_t>::max()},
        {"/render/seed", 0x1p64, {"render.seed = 18446744073709551616 is out of range"}, 0},
        {"/render/fiber_seed",
         -3,
         {"render.fiber_seed = -3 is out of range: allowed [0, 18446744073709551615]"},
         5},
        {"/render/sampler",
         "halton",
         {"render.sampler: expected one of \"independent\", \"sobol\", got the string \"halton\""},
         "independent"},
        {"/render/seed",
         0.5,
         {"render.seed: expected an integer in [0, 18446744073709551615], got 0.5"},
         nullptr},
        {"/lights",
         json::object(),
         {"lights: expected an array of objects, got an object"},
         json::array()},
        {"/lights/0", 3, {"lights[0]: expected an object, got 3"}, nullptr},
        {"/lights/0/type",
         "area",
         {"lights[0].type: expected one of \"sky\", \"envmap\", \"sphere\", \"constant\", "
          "\"point\", \"directional\", got "
          "the string \"area\""},
         nullptr},
        {"/lights/0/type",
         1,
         {"lights[0].type: expected one of \"sky\", \"envmap\", \"sphere\", \"constant\", "
          "\"point\", \"directional\", got 1"},
         nullptr},
        {"/lights/0/scale",
         -0.5,
         {"lights[0].scale = -0.5 is out of range: allowed [0, 1e+06]"},
         0},
        {"/lights/0/scale",
         1e308,
         {"lights[0].scale = 1e+308 is out of range: allowed [0, 1e+06]"},
         1e6},
        {"/lights/1/scale", -1e-300, {"lights[1].scale = -1e-300 is out of range"}, 0},
        {"/lights/1/rotate_deg", nan, {"lights[1].rotate_deg: expected a finite number"}, 3600},
        {"/lights/1/file",
         "",
         {"lights[1].file: expected a file name, got the empty string"},
         nullptr},
        {"/lights/1/file",
         "sky.png",
         {"lights[1].file: \"sky.png\" has an unsupported "
          "extension (allowed: .exr, .hdr)"},
         "sky.EXR"},
        {"/lights/1/file", std::string("a\0b.exr", 7), {"cannot contain a NUL"}, nullptr},
        {"/lights/1/file",
         json::array(),
         {"lights[1].file: expected a file name, got an array"},
         nullptr},
        {"/lights/2/radius",
         0,
         {"lights[2].radius = 0 is out of range: allowed [1e-06, 1e+06] scene units"},
         1e-6},
        {"/lights/2/center",
         json::array({1, 2, 3, 4}),
         {"lights[2].center: expected an array of 3 numbers in [-1e+06, 1e+06] scene units, got an "
          "array of 4"},
         nullptr},
        {"/lights/2/radiance",
         json::array({1, -1, 1}),
         {"lights[2].radiance[1] = -1 is out of range: allowed [0, 1e+06]"},
         json::array({0, 0, 0})},
        {"/lights/3/radiance",
         json::array({1, 1}),
         {"lights[3].radiance: expected an array of 3 numbers in [0, 1e+06] (r, g, b), got an "
          "array of 2"},
         nullptr},
        {"/lights/4/intensity",
         json::array({1, nan, 1}),
         {"lights[4].intensity[1]: expected a finite number in [0, 1e+06]"},
         json::array({0, 0, 1e6})},
        {"/lights/4/position",
         json::array({0, 2e6, 0}),
         {"lights[4].position[1] = 2e+06 is out of range: allowed [-1e+06, 1e+06] scene units"},
         json::array({0, -1e6, 0})},
        {"/lights/5/direction",
         json::array({0, 0, 0}),
         {"lights[5].direction: the direction the light travels cannot be 0"},
         json::array({0, 0, 1e-300})},
        {"/lights/5/irradiance",
         json::array({-1, 0, 0}),
         {"lights[5].irradiance[0] = -1 is out of range: allowed [0, 1e+06]"},
         nullptr},
        {"/yarns", "knit.bcc", {"yarns: expected an array of objects, got the string"}, nullptr},
        {"/yarns/0", json::array(), {"yarns[0]: expected an object, got an array of 0"}, nullptr},
        {"/yarns/0/curves",
         "knit.ply",
         {"yarns[0].curves: \"knit.ply\" has an unsupported "
          "extension (allowed: .bcc, .txt, .obj)"},
         "knit.Txt"},
        {"/yarns/0/curves", 7, {"yarns[0].curves: expected a file name, got 7"}, nullptr},
        {"/yarns/0/model", nullptr, {"yarns[0].model: expected a file name, got null"}, nullptr},
        {"/yarns/0/scale",
         0,
         {"yarns[0].scale = 0 is out of range: allowed [1e-06, 1e+06] scene units"},
         1e-6},
        {"/yarns/0/radius",
         -0.02,
         {"yarns[0].radius = -0.02 is out of range: allowed [1e-06, 1e+06] scene units"},
         1e-6},
        {"/yarns/0/radius",
         nullptr,
         {"yarns[0].radius: expected a number in [1e-06, 1e+06] scene units, got null"},
         nullptr},
        {"/yarns/0/plies", 17, {"yarns[0].plies = 17 is out of range: allowed [1, 16]"}, 16},
        {"/yarns/1/plies", 0, {"yarns[1].plies = 0 is out of range: allowed [1, 16]"}, 1},
        {"/yarns/0/plies", 3.5, {"yarns[0].plies: expected an integer in [1, 16], got 3.5"}, 3.0},
        {"/yarns/0/ply_twist",
         100.5,
         {"yarns[0].ply_twist = 100.5 is out of range: allowed "
          "[-100, 100]"},
         100},
        {"/yarns/0/ply_twist", -100.5, {"yarns[0].ply_twist = -100.5 is out of range"}, -100},
        {"/yarns/0/mode",
         "fibers",
         {"yarns[0].mode: expected one of \"neural\", \"fiber\", \"dual\", got the string "
          "\"fibers\""},
         "fiber"},
        {"/yarns/1/mode", 1, {"yarns[1].mode: expected one of \"neural\""}, "neural"},
    };
    for (const RangeCase& c : cases) {
        SCOPED_TRACE(c.pointer + " = " + c.bad.dump());
        const json bad = fullWith(c.pointer, c.bad);
        const auto expectMessage = [&](const std::function<void()>& parse) {
            try {
                parse();
                ADD_FAILURE() << "accepted";
            } catch (const InputError& e) {
                const std::string msg = e.what();
                EXPECT_EQ(msg.rfind("scene.json: ", 0), 0u) << msg;
                for (const std::string& p : c.message)
                    EXPECT_NE(msg.find(p), std::string::npos)
                        << "'" << msg << "' lacks '" << p << "'";
            }
        };
        expectMessage([&] { parseJson(bad); });
        // The same as text, where the JSON parser picks its own number types
        // (0 is unsigned there); NaN and infinity have no text (NaN != NaN).
        const std::string text = bad.dump();
        if (json::parse(text) == bad)
            expectMessage([&] { parseSceneText(text, "scene.json", "/data/scenes"); });
        if (!c.goodBoundary.is_null()) {
            const json good = fullWith(c.pointer, c.goodBoundary);
            EXPECT_NO_THROW(parseJson(good)) << c.goodBoundary.dump();
            EXPECT_NO_THROW(parseSceneText(good.dump(), "scene.json", "/data/scenes"))
                << c.goodBoundary.dump();
        }
    }
    // Boundary values land in the scene unchanged.
    EXPECT_EQ(parseJson(fullWith("/render/seed", std::numeric_limits<uint64_t>::max())).render.seed,
              std::numeric_limits<uint64_t>::max());
    EXPECT_EQ(parseJson(fullWith("/render/spp", 1e3)).render.spp, 1000);
    EXPECT_EQ(parseSceneText(R"({"camera": {"from": [0, 0, 1], "to": [0, 0, 0]},
                                 "render": {"seed": 18446744073709551615}})",
                             "s.json", "")
                  .render.seed,
              std::numeric_limits<uint64_t>::max());
    // One past 2^64 - 1 is read as a float by the JSON parser: still out of range.
    expectInputError(
        [] {
            parseSceneText(R"({"camera": {"from": [0, 0, 1], "to": [0, 0, 0]},
                               "render": {"seed": 18446744073709551616}})",
                           "s.json", "");
        },
        {"s.json: render.seed = 18446744073709551616 is out of range"});
    expectRejected(json::array({1}), {"scene.json: expected an object, got an array of 1"});
}

TEST(SceneFile, CameraGeometryIsChecked) {
    expectRejected(fullWith("/camera/to", json::array({0, 1.5, 4})),
                   {"scene.json: camera.to = [0, 1.5, 4] is out of range: allowed any point "
                    "other than camera.from"});
    // Parallel and antiparallel to to - from = (0, -1, -4); zero.
    for (const json& up : {json::array({0, -2, -8}), json::array({0, 0.5, 2}),
                           json::array({0, 0, 0}), json::array({0, -1e-300, -4e-300})}) {
        SCOPED_TRACE(up.dump());
        expectRejected(fullWith("/camera/up", up), {"scene.json: camera.up = [",
                                                    "is out of range: allowed any vector not "
                                                    "parallel to camera.to - camera.from"});
    }
    // Nearly parallel but not quite (2.4e-4 rad) is accepted; so are huge and
    // tiny coordinates whose difference does not overflow.
    EXPECT_NO_THROW(parseJson(fullWith("/camera/up", json::array({0, 1, 4 - 4.1e-3}))));
    json far = fullWith("/camera/from", json::array({1e6, 0, 0}));
    far[json::json_pointer("/camera/to")] = json::array({-1e6, 0, 0});
    EXPECT_NO_THROW(parseJson(far));
    // A tiny up vector is normalised, not refused (issue 18: it reached Embree as NaN).
    EXPECT_NO_THROW(parseJson(fullWith("/camera/up", json::array({0, 1e-300, 0}))));
    json tiny = fullWith("/camera/from", json::array({0, 0, 5e-324}));
    tiny[json::json_pointer("/camera/to")] = json::array({0, 0, 0});
    EXPECT_NO_THROW(parseJson(tiny));
    // Beyond what Embree's float can place (issue 18: an assertion inside Embree).
    expectRejected(fullWith("/camera/from", json::array({1.9e18, 0, 0})),
                   {"camera.from[0] = 1.9e+18 is out of range: allowed [-1e+06, 1e+06] scene units"});
}

TEST(SceneFile, MalformedJsonNamesLineAndColumn) {
    // Line 3 is `    "from": [0, 0, 1,]`; the parser stops at the ']'.
    expectInputError(
        [] { parseSceneText("{\n  \"camera\": {\n    \"from\": [0, 0, 1,]\n", "bad.json", ""); },
        {"bad.json:3:22: malformed JSON: syntax error while parsing value"});
    expectInputError([] { parseSceneText("", "empty.json", ""); },
                     {"empty.json:1:1: malformed JSON", "unexpected end of input"});
    expectInputError([] { parseSceneText("{\"camera\": {}}\n}", "trail.json", ""); },
                     {"trail.json:2:1: malformed JSON", "expected end of input"});
    expectInputError([] { parseSceneText("{\"camera\": {\"fov_deg\": 1e400}}", "big.json", ""); },
                     {"big.json:1:24: malformed JSON: number overflow parsing '1e400'"});
    expectInputError([] { parseSceneText("{\"a\": \"\xff\"}", "utf.json", ""); },
                     {"utf.json:1:8: malformed JSON", "UTF-8"});
    expectInputError([] { parseSceneText("{\"a\": NaN}", "nan.json", ""); },
                     {"nan.json:1:7: malformed JSON"});
}

TEST(SceneFile, DuplicateKeysAreErrorsNamingThePath) {
    expectInputError(
        [] {
            parseSceneText(R"({"camera": {"from": [0, 0, 1], "to": [0, 0, 0]},
                               "render": {"spp": 4, "spp": 8}})",
                           "dup.json", "");
        },
        {"dup.json: render: duplicate key \"spp\""});
    expectInputError(
        [] {
            parseSceneText(R"({"camera": {}, "lights": [{}, {"type": "sky", "type": "sky"}],
                               "camera": {}})",
                           "dup.json", "");
        },
        {"dup.json: lights[1]: duplicate key \"type\""});
    expectInputError([] { parseSceneText(R"({"camera": 1, "camera": 2})", "dup.json", ""); },
                     {"dup.json: duplicate key \"camera\""});
}

TEST(SceneFile, DeepNestingIsRejectedWithoutRecursion) {
    constexpr size_t kDeep = 100000;
    expectInputError([&] { parseSceneText(std::string(kDeep, '['), "deep.json", ""); },
                     {"deep.json:1:65: JSON nested deeper than 64 levels"});
    expectInputError(
        [&] { parseSceneText(std::string(kDeep, '[') + std::string(kDeep, ']'), "deep.json", ""); },
        {"deep.json:1:65: JSON nested deeper than 64 levels"});
    expectInputError([&] { parseSceneText("{\"a\":\n" + std::string(kDeep, '{'), "d.json", ""); },
                     {"d.json:2:64: JSON nested deeper than 64 levels"});
    // Brackets inside strings do not count.
    expectInputError(
        [&] {
            parseSceneText(
                "{\"camera\": {\"to\": [0, 0, 0], \"from\": \"" + std::string(kDeep, '[') + "\"}}",
                "s.json", "");
        },
        {"s.json: camera.from: expected an array of 3 numbers in [-1e+06, 1e+06] scene units, got the string \"[[[[", "...\""});
    // 64 levels parse as JSON; the schema then rejects the nesting.
    const std::string nested = std::string(62, '[') + std::string(62, ']');
    expectInputError(
        [&] {
            parseSceneText(
                R"({"camera": {"from": [0, 0, 1], "to": [0, 0, 0]}, "yarns": [)" + nested + "]}",
                "n.json", "");
        },
        {"n.json: yarns[0]: expected an object, got an array of 1"});
}

TEST(SceneFile, RelativePathsResolveAgainstTheBaseDir) {
    const std::string text = R"({"camera": {"from": [0, 0, 1], "to": [0, 0, 0]},
        "lights": [{"type": "envmap", "file": "/maps/sky.exr"}],
        "yarns": [{"curves": "sub/knit.bcc", "model": "../m.json"}]})";
    const SceneDesc a = parseSceneText(text, "a.json", "/data/scenes");
    EXPECT_EQ(a.lights[0]->as<EnvmapLightDesc>().file, "/maps/sky.exr");
    EXPECT_EQ(a.yarns[0].curves, "/data/scenes/sub/knit.bcc");
    EXPECT_EQ(a.yarns[0].model, "/data/scenes/../m.json");
    const SceneDesc b = parseSceneText(text, "b.json", "relative/dir");
    EXPECT_EQ(b.yarns[0].curves, "relative/dir/sub/knit.bcc");
    const SceneDesc c = parseSceneText(text, "c.json", "");
    EXPECT_EQ(c.yarns[0].curves, "sub/knit.bcc");
    EXPECT_EQ(c.yarns[0].model, "../m.json");
}

TEST(SceneFile, VertexColoursAreAFileBesideTheCurvesAndExcludeColour) {
    const std::string yarn = R"({"camera": {"from": [0, 0, 1], "to": [0, 0, 0]},
        "yarns": [{"curves": "knit.bcc", "model": "m.json", )";
    const SceneDesc s = parseSceneText(yarn + R"("vertex_colours": "dye/knit.txt"}]})",
                                       "scene.json", "/data");
    EXPECT_EQ(s.yarns[0].vertexColours, "/data/dye/knit.txt");
    EXPECT_FALSE(s.yarns[0].colour);
    EXPECT_EQ(toJson(s)["yarns"][0]["vertex_colours"], "/data/dye/knit.txt");
    EXPECT_EQ(parseScene(toJson(s), "again.json", "").yarns[0].vertexColours,
              "/data/dye/knit.txt");
    EXPECT_FALSE(toJson(parseSceneText(yarn + "\"plies\": 1}]}", "s.json", ""))["yarns"][0]
                     .contains("vertex_colours"));
    const std::vector<std::string> inputs = [&] {
        std::vector<std::string> names;
        for (const CommandPath& c : sceneInputs(s, "scene.json")) names.push_back(c.path);
        return names;
    }();
    EXPECT_NE(std::find(inputs.begin(), inputs.end(), "/data/dye/knit.txt"), inputs.end());
    expectInputError(
        [&] {
            parseSceneText(yarn + R"("colour": [1, 0, 0], "vertex_colours": "c.txt"}]})",
                           "scene.json", "");
        },
        {"scene.json: yarns[0].vertex_colours", "either \"colour\"", "not both"});
    expectInputError(
        [&] { parseSceneText(yarn + R"("vertex_colours": "c.bcc"}]})", "scene.json", ""); },
        {"yarns[0].vertex_colours", "c.bcc", ".txt"});
    expectInputError(
        [&] { parseSceneText(yarn + R"("vertex_colours": 3}]})", "scene.json", ""); },
        {"yarns[0].vertex_colours", "file name"});
}

// "appearance" (docs/colour.md): sRGB as [r, g, b] or "#rrggbb", written
// back as numbers and only when given (so a scene without it keeps its hash),
// excluding "colour" and "vertex_colours".
TEST(SceneFile, AppearanceIsAnSrgbColourExcludingColourAndVertexColours) {
    const std::string yarn = R"({"camera": {"from": [0, 0, 1], "to": [0, 0, 0]},
        "yarns": [{"curves": "knit.bcc", "model": "m.json", )";
    const SceneDesc hex = parseSceneText(yarn + R"("appearance": "#FF8000"}]})", "s.json", "");
    ASSERT_TRUE(hex.yarns[0].appearance);
    EXPECT_EQ(*hex.yarns[0].appearance, Rgb(1.0, 128 / 255.0, 0.0));
    const SceneDesc array =
        parseSceneText(yarn + R"("appearance": [1, 0.50196078431372548, 0]}]})", "s.json", "");
    EXPECT_EQ(*array.yarns[0].appearance, *hex.yarns[0].appearance);
    EXPECT_EQ(toJson(array), toJson(hex));  // what the scene hash reads besides the files
    EXPECT_EQ(*parseScene(toJson(hex), "again.json", "").yarns[0].appearance,
              *hex.yarns[0].appearance);
    EXPECT_FALSE(toJson(parseSceneText(yarn + "\"plies\": 1}]}", "s.json", ""))["yarns"][0]
                     .contains("appearance"));
    expectInputError(
        [&] { parseSceneText(yarn + R"("appearance": "#ff80"}]})", "s.json", ""); },
        {"s.json: yarns[0].appearance", "#rrggbb", "\"#ff80\""});
    expectInputError(
        [&] { parseSceneText(yarn + R"("appearance": "#gg8000"}]})", "s.json", ""); },
        {"yarns[0].appearance", "#rrggbb"});
    expectInputError(
        [&] { parseSceneText(yarn + R"("appearance": [1.5, 0, 0]}]})", "s.json", ""); },
        {"yarns[0].appearance", "[0, 1]"});
    expectInputError(
        [&] {
            parseSceneText(yarn + R"("appearance": [1, 0, 0], "colour": [1, 0, 0]}]})", "s.json",
                           "");
        },
        {"yarns[0].appearance", "not both"});
    expectInputError(
        [&] {
            parseSceneText(yarn + R"("appearance": [1, 0, 0], "vertex_colours": "c.txt"}]})",
                           "s.json", "");
        },
        {"yarns[0].vertex_colours", "not both"});
}

TEST_F(SceneFileTest, LoadSceneResolvesAgainstTheSceneFolder) {
    std::filesystem::create_directories(dir_ / "scenes");
    const std::string file = path("scenes/scene.json");
    writeFileAtomic(file, R"({"camera": {"from": [0, 0, 1], "to": [0, 0, 0]},
        "yarns": [{"curves": "knit.bcc", "model": "/models/m.json"}]})");
    const SceneDesc s = loadScene(file);
    EXPECT_EQ(s.path, file);
    EXPECT_EQ(std::filesystem::path(s.baseDir), dir_ / "scenes");
    EXPECT_EQ(std::filesystem::path(s.yarns[0].curves), dir_ / "scenes" / "knit.bcc");
    EXPECT_EQ(s.yarns[0].model, "/models/m.json");
    // Errors name the file as it was given.
    writeFileAtomic(file, "{\"camera\": 1}");
    expectInputError([&] { loadScene(file); }, {file + ": camera: expected an object"});
    expectInputError([&] { loadScene(path("missing.json")); }, {path("missing.json")});
}

TEST(SceneFile, ToJsonRoundTripsFieldByField) {
    for (const std::string& text : {kFullScene, kMinimalScene}) {
        const SceneDesc s = parseSceneText(text, "scene.json", "/data/scenes");
        const json j = toJson(s);
        // Every key is written, defaults included.
        for (const char* key : {"camera", "film", "render", "lights", "yarns"})
            EXPECT_TRUE(j.contains(key)) << key;
        for (const char* key : {"from", "to", "up", "fov_deg"})
            EXPECT_TRUE(j["camera"].contains(key)) << key;
        const SceneDesc back = parseScene(j, "scene.json", "/data/scenes");
        EXPECT_TRUE(differences(s, back).empty()) << joined(differences(s, back));
        const SceneDesc viaText = parseSceneText(j.dump(2), "scene.json", "/data/scenes");
        EXPECT_TRUE(differences(s, viaText).empty()) << joined(differences(s, viaText));
    }
    // Values that a lossy number format would change.
    SceneDesc s = parseSceneText(kFullScene, "scene.json", "/data/scenes");
    s.camera.fovDeg = 0.1 + 0.2;
    editLight<SphereLightDesc>(s, 2, [](auto& l) { l.radius = std::nextafter(1e-6, 1.0); });
    editLight<EnvmapLightDesc>(s, 1, [](auto& l) { l.rotateDeg = -1.0 / 3.0; });
    s.render.seed = std::numeric_limits<uint64_t>::max();
    s.render.fiberSeed = std::numeric_limits<uint64_t>::max() - 1;
    s.yarns[1].radius = 1.0 / 3e5;
    const SceneDesc back = parseScene(json::parse(toJson(s).dump()), "scene.json", "/data/scenes");
    EXPECT_TRUE(differences(s, back).empty()) << joined(differences(s, back));
    // Only the keys of each light's own type are written.
    const json lights = toJson(s)["lights"];
    EXPECT_FALSE(lights[0].contains("radiance"));
    EXPECT_FALSE(lights[3].contains("scale"));
}

class SceneHashTest : public testing::TempDirTest {
  protected:
    // A scene folder with a curve file, a model and an environment map.
    void writeScene(const std::filesystem::path& folder, const std::string& sceneText) {
        std::filesystem::create_directories(folder / "maps");
        writeFileAtomic((folder / "knit.bcc").string(), std::string("BCC\x44 curve bytes", 16));
        writeFileAtomic((folder / "model.json").string(), "{\"format\": \"model\"}");
        writeFileAtomic((folder / "maps" / "sky.exr").string(), "exr bytes");
        writeFileAtomic((folder / "dye.txt").string(), "1 0 0\n0 0 1\n");
        writeFileAtomic((folder / "scene.json").string(), sceneText);
    }
    static std::string hashOf(const std::filesystem::path& sceneFile) {
        return sceneHash(loadScene(sceneFile.string()));
    }

    const std::string scene_ = R"({"camera": {"from": [0, 0, 1], "to": [0, 0, 0]},
        "render": {"spp": 16},
        "lights": [{"type": "envmap", "file": "maps/sky.exr"}, {"type": "sky"}],
        "yarns": [{"curves": "knit.bcc", "model": "model.json", "plies": 3},
                  {"curves": "knit.bcc", "model": "model.json", "vertex_colours": "dye.txt"}]})";
};

TEST_F(SceneHashTest, StableAcrossFoldersAndSensitiveToEveryInput) {
    writeScene(dir_ / "a", scene_);
    const std::string h = hashOf(dir_ / "a" / "scene.json");
    ASSERT_EQ(h.size(), 16u);
    EXPECT_EQ(h.find_first_not_of("0123456789abcdef"), std::string::npos) << h;
    EXPECT_EQ(hashOf(dir_ / "a" / "scene.json"), h);

    // The same folder elsewhere, under another name: the same hash.
    std::filesystem::create_directories(dir_ / "copy");
    std::filesystem::copy(dir_ / "a", dir_ / "copy" / "elsewhere",
                          std::filesystem::copy_options::recursive);
    EXPECT_EQ(hashOf(dir_ / "copy" / "elsewhere" / "scene.json"), h);

    // One byte of any referenced file changes it.
    for (const char* file : {"knit.bcc", "model.json", "maps/sky.exr", "dye.txt"}) {
        SCOPED_TRACE(file);
        writeScene(dir_ / "b", scene_);
        const std::string p = (dir_ / "b" / file).string();
        std::string bytes = readFile(p);
        bytes[1] ^= 1;
        writeFileAtomic(p, bytes);
        EXPECT_NE(hashOf(dir_ / "b" / "scene.json"), h);
    }

    // Any parameter changes it.
    const SceneDesc base = loadScene((dir_ / "a" / "scene.json").string());
    std::vector<std::pair<std::string, SceneDesc>> variants;
    const auto variant = [&](const std::string& name, auto edit) {
        SceneDesc s = base;
        edit(s);
        variants.emplace_back(name, s);
    };
    variant("spp", [](SceneDesc& s) { s.render.spp = 17; });
    variant("seed", [](SceneDesc& s) { s.render.seed = 1; });
    variant("fiber_seed", [](SceneDesc& s) { s.render.fiberSeed = 1; });
    variant("max_depth", [](SceneDesc& s) { s.render.maxDepth = 99; });
    variant("width", [](SceneDesc& s) { s.film.width = 511; });
    variant("fov", [](SceneDesc& s) { s.camera.fovDeg = std::nextafter(30.0, 31.0); });
    variant("up", [](SceneDesc& s) { s.camera.up = {0, 1, 1e-9}; });
    variant("envmap scale", [](SceneDesc& s) {
        editLight<EnvmapLightDesc>(s, 0, [](auto& l) { l.scale = 2; });
    });
    variant("sky scale", [](SceneDesc& s) {
        editLight<SkyLightDesc>(s, 1, [](auto& l) { l.scale = 0.5; });
    });
    variant("light order", [](SceneDesc& s) { std::swap(s.lights[0], s.lights[1]); });
    variant("no lights", [](SceneDesc& s) { s.lights.clear(); });
    variant("plies", [](SceneDesc& s) { s.yarns[0].plies = 2; });
    variant("twist", [](SceneDesc& s) { s.yarns[0].plyTwist = 0.1; });
    variant("radius", [](SceneDesc& s) { s.yarns[1].radius = 0.01; });
    variant("scale", [](SceneDesc& s) { s.yarns[1].scale = 2; });
    variant("one yarn", [](SceneDesc& s) { s.yarns.pop_back(); });
    variant("mode", [](SceneDesc& s) { s.yarns[0].mode = "fiber"; });
    for (const auto& [name, s] : variants) EXPECT_NE(sceneHash(s), h) << name;
    // Where the scene file is and what it is called are not part of it.
    SceneDesc renamed = base;
    renamed.path = "other.json";
    renamed.baseDir = "/nowhere";
    EXPECT_EQ(sceneHash(renamed), h);

    // A missing file is an InputError naming it and the key that refers to it.
    std::filesystem::remove(dir_ / "a" / "model.json");
    const std::string model = (dir_ / "a" / "model.json").string();
    expectInputError([&] { sceneHash(base); }, {"yarns[0].model", model});
}

// ---------------------------------------------------------------------------
// Fuzz: mutated scene texts are parsed or rejected with an InputError, never
// anything else; what is accepted satisfies the documented ranges and
// survives a round trip.

class Mutator {
  public:
    explicit Mutator(uint64_t seed) : rng_(0, seed) {}

    size_t below(size_t n) { return static_cast<size_t>(rng_.uniform() * static_cast<double>(n)); }
    template <typename T>
    const T& pick(const std::vector<T>& v) {
        return v[below(v.size())];
    }

    // One number set to a value near a documented range boundary (either side).
    void boundaryMutation(json* root) {
        std::vector<Node> numbers;
        for (const Node& n : nodes(root))
            if (n.value->is_number()) numbers.push_back(n);
        if (!numbers.empty()) *pick(numbers).value = pick(boundaryValues());
    }

    // The same on text: one number token replaced by a boundary value's text
    // (the JSON parser reads 0 as unsigned, 0.0 as a double).
    void boundaryTextMutation(std::string* s) {
        static const std::vector<std::string> texts = split(
            "0 -0 0.0 1 -1 1e-300 0.5 16 17 16384 16385 1048576 1048577 10000 10001 100 100.5 "
            "-100 -100.5 179.9 180 2.0 2.5 1e3 1e-3 18446744073709551615 18446744073709551616 "
            "-9223372036854775808");
        std::vector<std::pair<size_t, size_t>> numbers;
        for (const auto& t : tokenize(*s)) {
            const char c = (*s)[t.first];
            if (c == '-' || (c >= '0' && c <= '9')) numbers.push_back(t);
        }
        const auto t = pick(numbers);
        s->replace(t.first, t.second, pick(texts));
    }

    // Structural changes of a valid tree: dump() of the result is valid JSON.
    void treeMutation(json* root) {
        const Node n = pick(nodes(root));
        switch (below(5)) {
            case 0:  // drop the key or element
                if (n.parent == nullptr) break;
                if (n.parent->is_array())
                    n.parent->erase(n.index);
                else
                    n.parent->erase(n.key);
                break;
            case 1:
                *n.value = pick(values());
                break;
            case 2:  // an unknown key
                if (n.value->is_object()) (*n.value)["extra" + std::to_string(below(3))] = 1;
                break;
            case 3:
                *n.value = json::array({*n.value});
                break;
            default:
                boundaryMutation(root);
                break;
        }
    }

    // Byte and token changes: mostly invalid JSON.
    void textMutation(std::string* s) {
        const auto tokens = tokenize(*s);
        switch (below(9)) {
            case 0: {  // delete bytes
                const size_t at = below(s->size() + 1);
                s->erase(at, 1 + below(8));
                break;
            }
            case 1: {  // insert bytes
                const std::string alphabet = "{}[]\",:.-+eE0123456789 \n\\tfnul";
                std::string bytes;
                for (size_t k = 0, n = 1 + below(4); k < n; ++k)
                    bytes += below(4) == 0 ? static_cast<char>(below(256))
                                           : alphabet[below(alphabet.size())];
                s->insert(below(s->size() + 1), bytes);
                break;
            }
            case 2:  // replace a byte
                if (!s->empty()) (*s)[below(s->size())] = static_cast<char>(below(256));
                break;
            case 3: {  // swap two tokens
                if (tokens.size() < 2) break;
                auto a = pick(tokens), b = pick(tokens);
                if (a.first > b.first) std::swap(a, b);
                if (a.first + a.second > b.first) break;
                const std::string ta = s->substr(a.first, a.second);
                const std::string tb = s->substr(b.first, b.second);
                s->replace(b.first, b.second, ta);
                s->replace(a.first, a.second, tb);
                break;
            }
            case 4: {  // replace a number or literal
                std::vector<std::pair<size_t, size_t>> numbers;
                for (const auto& t : tokens) {
                    const char c = (*s)[t.first];
                    if (c == '-' || (c >= '0' && c <= '9') || c == 't' || c == 'f' || c == 'n')
                        numbers.push_back(t);
                }
                if (numbers.empty()) break;
                const auto t = pick(numbers);
                s->replace(t.first, t.second, pick(numberTexts()));
                break;
            }
            case 5: {  // duplicate a key with its value, in the same object
                for (size_t k = 0; k + 2 < tokens.size(); ++k) {
                    const size_t i = below(tokens.size() - 2);
                    if ((*s)[tokens[i].first] != '"' || (*s)[tokens[i + 1].first] != ':') continue;
                    const auto& v = tokens[i + 2];
                    const std::string pair =
                        s->substr(tokens[i].first, v.first + v.second - tokens[i].first);
                    s->insert(v.first + v.second, ", " + pair);
                    break;
                }
                break;
            }
            case 6: {  // nest deeply, sometimes balanced
                static const std::vector<size_t> depths = {63, 64, 65, 1000, 10000};
                const size_t n = below(200) == 0 ? 100000 : pick(depths);
                const char open = below(2) ? '[' : '{';
                std::string nest(n, open);
                if (below(2)) nest += std::string(n, open == '[' ? ']' : '}');
                s->insert(below(s->size() + 1), nest);
                break;
            }
            case 7:  // truncate
                s->resize(below(s->size() + 1));
                break;
            default: {  // replace a token with another value text
                if (tokens.empty()) break;
                const auto t = pick(tokens);
                s->replace(t.first, t.second, pick(numberTexts()));
                break;
            }
        }
    }

  private:
    // A value in the tree and where it sits (parent null for the root).
    struct Node {
        json* value;
        json* parent;
        std::string key;  // in an object parent
        size_t index;     // in an array parent
    };

    static std::vector<Node> nodes(json* root) {
        std::vector<Node> out = {{root, nullptr, {}, 0}};
        for (size_t k = 0; k < out.size(); ++k) {
            json* v = out[k].value;
            if (v->is_object())
                for (auto it = v->begin(); it != v->end(); ++it)
                    out.push_back({&it.value(), v, it.key(), 0});
            if (v->is_array())
                for (size_t i = 0; i < v->size(); ++i) out.push_back({&(*v)[i], v, {}, i});
        }
        return out;
    }

    static const std::vector<json>& values() {
        static const std::vector<json> v = {
            json(std::numeric_limits<double>::quiet_NaN()),
            json(std::numeric_limits<double>::infinity()),
            json(-std::numeric_limits<double>::infinity()),
            json(1e308),
            json(-1),
            json(0),
            json(-0.0),
            json(1),
            json(2.5),
            json(16),
            json(uint64_t{1} << 63),
            json(std::numeric_limits<int64_t>::min()),
            json("str"),
            json(""),
            json("knit.bcc"),
            json(nullptr),
            json(true),
            json::array(),
            json::object(),
            json::array({1, 2}),
            json::array({1, 2, 3}),
            json::array({0, 0, 0}),
            json::array({1, 2, 3, 4}),
            json::object({{"type", "sky"}}),
        };
        return v;
    }

    // Both sides of every range boundary in scene_file.h.
    static const std::vector<json>& boundaryValues() {
        static const std::vector<json> v = {
            json(0),     json(-0.0),  json(1),     json(-1),    json(1e-300),  json(0.5),
            json(16),    json(17),    json(16384), json(16385), json(1 << 20), json((1 << 20) + 1),
            json(10000), json(10001), json(100),   json(100.5), json(-100),    json(-100.5),
            json(179.9), json(180),   json(2.0),   json(2.5),   json(1e3),     json(1e-3)};
        return v;
    }

    static const std::vector<std::string>& numberTexts() {
        // Number-like and other value texts a hand-written scene might hold.
        static const std::vector<std::string> v = split(
            "NaN -nan Infinity -Infinity 1e400 -1e400 1e-400 1e308 -1 0 -0 2.5 "
            "18446744073709551616 -9223372036854775809 99999999999999999999999 \"12\" null "
            "true [] {} [1,2,3] 0x10 01 1. .5 1e \"\\u0000\" \"\\ud800\" \"\xc3\x28\"");
        return v;
    }

    // The words of a space-separated list.
    static std::vector<std::string> split(const std::string& all) {
        std::vector<std::string> out;
        for (size_t at = 0; at < all.size();) {
            const size_t end = std::min(all.find(' ', at), all.size());
            out.push_back(all.substr(at, end - at));
            at = end + 1;
        }
        return out;
    }

    // (offset, length) of each JSON token: strings, numbers, words, punctuation.
    static std::vector<std::pair<size_t, size_t>> tokenize(const std::string& s) {
        std::vector<std::pair<size_t, size_t>> tokens;
        for (size_t i = 0; i < s.size();) {
            const char c = s[i];
            size_t j = i + 1;
            if (c == ' ' || c == '\n' || c == '\t' || c == '\r') {
                ++i;
                continue;
            }
            if (c == '"') {
                while (j < s.size() && s[j] != '"') j += s[j] == '\\' ? 2 : 1;
                j = std::min(j + 1, s.size());
            } else if (c == '-' || (c >= '0' && c <= '9')) {
                while (j < s.size() &&
                       std::string_view("0123456789.eE+-").find(s[j]) != std::string_view::npos)
                    ++j;
            } else if (c >= 'a' && c <= 'z') {
                while (j < s.size() && s[j] >= 'a' && s[j] <= 'z') ++j;
            }
            tokens.emplace_back(i, j - i);
            i = j;
        }
        return tokens;
    }

    Rng rng_;
};

// What parseScene promises about anything it accepts.
void checkAccepted(const SceneDesc& s, bool roundTrip, std::vector<std::string>* failures,
                   size_t index) {
    std::vector<std::string> broken;
    const auto check = [&](bool ok, const char* what) {
        if (!ok) broken.push_back(what);
    };
    check(isFinite(s.camera.from) && isFinite(s.camera.to) && isFinite(s.camera.up), "finite");
    check(!(s.camera.from == s.camera.to), "from != to");
    check(s.camera.fovDeg > 0 && s.camera.fovDeg < 180, "fov");
    check(s.film.width >= 1 && s.film.width <= 16384, "width");
    check(s.film.height >= 1 && s.film.height <= 16384, "height");
    check(s.render.spp >= 1 && s.render.spp <= 1 << 20, "spp");
    check(s.render.maxDepth >= 1 && s.render.maxDepth <= 10000, "max_depth");
    const auto nonNegative = [](const Rgb& c) {
        return c.isFinite() && c.r >= 0 && c.g >= 0 && c.b >= 0;
    };
    for (const auto& light : s.lights) {
        if (const auto* sky = dynamic_cast<const SkyLightDesc*>(light.get())) {
            check(std::isfinite(sky->scale) && sky->scale >= 0, "light scale");
        } else if (const auto* env = dynamic_cast<const EnvmapLightDesc*>(light.get())) {
            check(std::isfinite(env->scale) && env->scale >= 0, "light scale");
            check(std::isfinite(env->rotateDeg), "rotate_deg");
            check(!env->file.empty(), "file");
        } else if (const auto* sphere = dynamic_cast<const SphereLightDesc*>(light.get())) {
            check(std::isfinite(sphere->radius) && sphere->radius > 0, "sphere radius");
            check(isFinite(sphere->center), "sphere center");
            check(nonNegative(sphere->radiance), "radiance");
        } else if (const auto* point = dynamic_cast<const PointLightDesc*>(light.get())) {
            check(isFinite(point->position), "point position");
            check(nonNegative(point->intensity), "intensity");
        } else if (const auto* sun = dynamic_cast<const DirectionalLightDesc*>(light.get())) {
            check(isFinite(sun->direction) && !(sun->direction == Vec3(0, 0, 0)), "direction");
            check(nonNegative(sun->irradiance), "irradiance");
        } else {
            check(nonNegative(light->as<ConstantLightDesc>().radiance), "radiance");
        }
    }
    for (const YarnDesc& y : s.yarns) {
        check(!y.curves.empty() && !y.model.empty(), "yarn files");
        check(std::isfinite(y.scale) && y.scale > 0, "yarn scale");
        check(!y.radius || (std::isfinite(*y.radius) && *y.radius > 0), "yarn radius");
        check(y.plies >= 1 && y.plies <= 16, "plies");
        check(std::isfinite(y.plyTwist) && std::fabs(y.plyTwist) <= 100, "ply_twist");
        check(y.mode.empty() || y.mode == "neural" || y.mode == "fiber" || y.mode == "dual",
              "mode");
    }
    // Outside the caller's catch: an accepted scene whose JSON is rejected fails.
    if (roundTrip) {
        try {
            const SceneDesc back = parseScene(toJson(s), s.path, s.baseDir);
            const std::vector<std::string> diff = differences(s, back);
            broken.insert(broken.end(), diff.begin(), diff.end());
        } catch (const std::exception& e) {
            broken.push_back(std::string("round trip threw: ") + e.what());
        }
    }
    if (!broken.empty())
        failures->push_back("case " + std::to_string(index) + ": " + joined(broken));
}

TEST(SceneFileFuzz, MutatedScenesParseOrThrowInputError) {
    const auto start = std::chrono::steady_clock::now();
    // Fewer (but still over 10 000) under the sanitizers, where a parse costs 7x.
    constexpr size_t kCases = testing::sampleScale() < 1 ? 10200 : 12000;
    const json base = json::parse(kFullScene);
    ASSERT_NO_THROW(parseScene(base, "fuzz.json", "/fuzz"));

    Mutator m(2024);
    size_t accepted = 0, rejected = 0;
    std::vector<std::string> failures;
    // Runs one parse; any exception but InputError is a failure of the test.
    // Every accepted scene is checked against the documented ranges, every
    // fourth also for its round trip through toJson (the costly part under
    // the sanitizers).
    const auto run = [&](size_t index, const std::string& text, const auto& parse) {
        std::optional<SceneDesc> scene;
        try {
            scene = parse();
        } catch (const InputError&) {
            ++rejected;
            return;
        } catch (const std::exception& e) {
            failures.push_back("case " + std::to_string(index) + " threw " + typeid(e).name() +
                               " (" + e.what() + ") on " + text.substr(0, 300));
            return;
        }
        ++accepted;
        checkAccepted(*scene, index % 4 == 0, &failures, index);
    };

    // A third each: one number at a range boundary; structural tree changes
    // (parsed as a tree, which may hold NaN, then as text); byte and token
    // changes of the text.
    for (size_t i = 0; i < kCases; ++i) {
        std::string text = kFullScene;
        size_t textMutations = 1 + m.below(3);
        if (i % 3 == 0) {
            m.boundaryTextMutation(&text);
            textMutations = 0;
        } else if (i % 3 == 1) {
            json j = base;
            for (size_t k = 0, n = 1 + m.below(3); k < n; ++k) m.treeMutation(&j);
            text = j.dump(m.below(2) ? -1 : 2);
            run(i, text, [&] { return parseScene(j, "fuzz.json", "/fuzz"); });
            textMutations = m.below(2);
        }
        for (size_t k = 0; k < textMutations; ++k) m.textMutation(&text);
        run(i, text, [&] { return parseSceneText(text, "fuzz.json", "/fuzz"); });
    }

    for (size_t k = 0; k < std::min<size_t>(failures.size(), 20); ++k) ADD_FAILURE() << failures[k];
    EXPECT_TRUE(failures.empty()) << failures.size() << " failing cases";
    // Both outcomes must be common, or the mutations test nothing.
    EXPECT_GT(accepted, kCases / 20);
    EXPECT_GT(rejected, kCases / 2);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf(
        "[ fuzz     ] %zu mutated scenes, %zu parses (%zu accepted, %zu rejected) in "
        "%.2f s\n",
        kCases, accepted + rejected, accepted, rejected, seconds);
    EXPECT_GE(kCases, 10000u);
}

// Issue 43, item 5: frame patterns and the turntable.
TEST(SceneAnimation, FramePatternsAndTheTurntable) {
    EXPECT_EQ(frameFileName("knit.%04d.bcc", 7, "c"), "knit.0007.bcc");
    EXPECT_EQ(frameFileName("knit.%d.bcc", 12345, "c"), "knit.12345.bcc");
    EXPECT_EQ(frameFileName("knit.%02d.bcc", 123, "c"), "knit.123.bcc");
    EXPECT_EQ(frameFileName("plain.bcc", 3, "c"), "plain.bcc");
    EXPECT_TRUE(hasFramePattern("a%d.txt"));
    EXPECT_FALSE(hasFramePattern("a.txt"));
    weft::testing::expectInputError([] { frameFileName("a%d%d.txt", 1, "yarns[0].curves"); },
                                    {"yarns[0].curves", "more than one"});
    weft::testing::expectInputError([] { frameFileName("a%s.txt", 1, "yarns[0].curves"); },
                                    {"yarns[0].curves", "%0Nd"});
    SceneDesc s;
    s.camera.from = {0, 1, 2};
    s.camera.to = {0, 1, 0};
    s.animation = {10, 13, 360};
    // Frame 11 of 10..13: a quarter turn about +y through `to`.
    const SceneDesc f = sceneAtFrame(s, 11, 10, 13);
    EXPECT_NEAR(f.camera.from.x, 2, 1e-12);
    EXPECT_NEAR(f.camera.from.y, 1, 1e-12);
    EXPECT_NEAR(f.camera.from.z, 0, 1e-12);
    EXPECT_EQ(f.camera.to, s.camera.to);
    EXPECT_EQ(sceneAtFrame(s, 10, 10, 13).camera.from, s.camera.from);
}

}  // namespace
}  // namespace weft::render
