// Mitsuba 3 scene files in and out (mitsuba.h): the paper's evaluation scene
// imports and renders, the camera's field of view against its formula, a
// B-spline against its analytic line, import -> export -> import is the
// identity, and what is outside the subset is refused with file, line and path.
#include "weft/render/mitsuba.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include "weft/core/curves.h"
#include "weft/core/file.h"
#include "weft/core/image_io.h"
#include "weft/core/math.h"
#include "weft/core/test_util.h"
#include "weft/render/renderer.h"
#include "weft/render/scene.h"
#include "weft/render/scene_objects.h"
#include "weft/yarn/yarn_model.h"

namespace weft::render {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using weft::testing::expectInputError;

const std::string kModel = std::string(WEFT_SOURCE_DIR) + "/tests/data/fleece-small.json";

// The same JSON up to 1e-9 relative in its numbers (what %.9g text keeps).
void expectSameScene(const json& a, const json& b, const std::string& where = "scene") {
    if (a.is_number() && b.is_number()) {
        const double x = a.get<double>(), y = b.get<double>();
        EXPECT_NEAR(x, y, 1e-9 * std::max(1.0, std::abs(y))) << where;
        return;
    }
    ASSERT_EQ(a.type(), b.type()) << where;
    if (a.is_object()) {
        ASSERT_EQ(a.size(), b.size()) << where << ": " << a.dump() << " vs " << b.dump();
        for (auto it = b.begin(); it != b.end(); ++it) {
            ASSERT_TRUE(a.contains(it.key())) << where << "." << it.key();
            expectSameScene(a[it.key()], it.value(), where + "." + it.key());
        }
    } else if (a.is_array()) {
        ASSERT_EQ(a.size(), b.size()) << where;
        for (size_t i = 0; i < a.size(); ++i)
            expectSameScene(a[i], b[i], where + "[" + std::to_string(i) + "]");
    } else {
        EXPECT_EQ(a, b) << where;
    }
}

class MitsubaTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("weft-mitsuba-" + std::to_string(::getpid()) + "-" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
        write("yarn.txt", "-1 0 0 0.5\n1 0 0 0.5\n");
    }
    void TearDown() override { fs::remove_all(dir_); }

    std::string write(const std::string& name, const std::string& text) {
        const fs::path p = dir_ / name;
        fs::create_directories(p.parent_path());
        std::ofstream(p) << text;
        return p.string();
    }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }

    fs::path dir_;
};

// Shaped like the paper's evaluation scene (its section 7): the path
// integrator without a depth limit, two sphere lights, a perspective camera,
// a 256 x 256 film, one curve file of a 2-point curve of radius 0.5.
const char* kPaperScene = R"(<?xml version="1.0"?>
<scene version="3.0.0">
    <default name="spp" value="64"/>
    <integrator type="path">
        <integer name="max_depth" value="-1"/>
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="30"/>
        <transform name="to_world">
            <lookat origin="0, 0, 8" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="256"/>
            <integer name="height" value="256"/>
            <rfilter type="box"/>
        </film>
    </sensor>
    <shape type="sphere">
        <point name="center" value="3, 4, 5"/>
        <float name="radius" value="0.5"/>
        <emitter type="area">
            <rgb name="radiance" value="20, 20, 20"/>
        </emitter>
    </shape>
    <shape type="sphere">
        <transform name="to_world">
            <scale value="0.25"/>
            <translate x="-3" y="2" z="4"/>
        </transform>
        <emitter type="area">
            <rgb name="radiance" value="10"/>
        </emitter>
    </shape>
    <bsdf type="diffuse" id="ply"/>
    <shape type="linearcurve">
        <string name="filename" value="yarn.txt"/>
        <ref id="ply"/>
    </shape>
</scene>
)";

TEST_F(MitsubaTest, ThePapersSceneImportsAndRenders) {
    const std::string xml = write("paper.xml", kPaperScene);
    MitsubaImportOptions options;
    options.model = kModel;
    options.defines = {{"spp", "4"}};  // -D over <default>
    const MitsubaImport im = importMitsubaScene(xml, options);
    const json& s = im.scene;
    EXPECT_EQ(s["render"]["max_depth"], 10000);
    EXPECT_EQ(s["render"]["spp"], 4);
    EXPECT_EQ(s["render"]["sampler"], "independent");
    EXPECT_EQ(s["film"]["width"], 256);
    EXPECT_EQ(s["camera"]["from"], json({0.0, 0.0, 8.0}));
    // fov across x of a square film is across the shorter side as it is.
    EXPECT_NEAR(s["camera"]["fov_deg"].get<double>(), 30.0, 1e-9);
    ASSERT_EQ(s["lights"].size(), 2u);
    EXPECT_EQ(s["lights"][0]["center"], json({3.0, 4.0, 5.0}));
    EXPECT_EQ(s["lights"][1]["center"], json({-3.0, 2.0, 4.0}));
    EXPECT_DOUBLE_EQ(s["lights"][1]["radius"].get<double>(), 0.25);
    EXPECT_EQ(s["lights"][1]["radiance"], json({10.0, 10.0, 10.0}));
    ASSERT_EQ(s["yarns"].size(), 1u);
    EXPECT_EQ(s["yarns"][0]["curves"], "curves/yarn.txt");
    EXPECT_EQ(s["yarns"][0]["model"], "models/fleece-small.json");

    // Written as a folder, it renders (a small film: the test's time).
    writeSceneFolder(
        [&] {
            auto files = im.files;
            json small = s;
            small["film"] = {{"width", 24}, {"height", 24}};
            files.push_back({"scene.json", small.dump(2)});
            return files;
        }(),
        path("out"));
    const SceneDesc desc = loadScene(path("out/scene.json"));
    const Scene scene(desc, SceneOptions{});
    RenderOptions r;
    r.spp = 2;
    r.quiet = true;
    const RenderResult result = render(scene, r);
    double yarn = 0;
    for (int x = 0; x < 24; ++x) yarn += result.image.get(x, 12).r;  // the row through the yarn
    EXPECT_GT(yarn, 0);
    EXPECT_EQ(result.image.get(12, 0).r, 0);  // no sky: Mitsuba's scene has no environment
}

TEST_F(MitsubaTest, FieldOfViewAxesBecomeTheShorterSide) {
    // 256 x 128, fov 60 across x: the shorter side (y) sees 2 atan(tan(30) / 2).
    const double expected = 2 * std::atan(std::tan(kPi / 6) / 2) * 180 / kPi;
    for (const auto& [axis, fov] : std::vector<std::pair<std::string, double>>{
             {"x", 60},
             {"larger", 60},
             {"y", expected},
             {"smaller", expected},
             {"diagonal", 2 * std::atan(std::tan(kPi / 6) * std::hypot(2, 1) / 2) * 180 / kPi}}) {
        const std::string xml =
            write("fov-" + axis + ".xml",
                  R"(<scene version="3.0.0"><sensor type="perspective"><float name="fov" value=")" +
                      std::to_string(fov) + R"("/><string name="fov_axis" value=")" + axis +
                      R"("/><film type="hdrfilm"><integer name="width" value="256"/>)"
                      R"(<integer name="height" value="128"/></film></sensor></scene>)");
        const MitsubaImport im = importMitsubaScene(xml, {});
        EXPECT_NEAR(im.scene["camera"]["fov_deg"].get<double>(), expected, 1e-5) << axis;
    }
}

TEST_F(MitsubaTest, BsplineCurvesFollowTheirSpline) {
    // Equally spaced points on a line: the cubic B-spline is the line from the
    // second point to the third, at its own speed; radii 1, 2, 3, 4 give 2 to 3.
    write("spline.txt", "0 0 0 1\n1 0 0 2\n2 0 0 3\n3 0 0 4\n");
    const std::string xml = write(
        "b.xml",
        R"(<scene version="3.0.0"><sensor type="perspective"><float name="fov" value="30"/></sensor>
<shape type="bsplinecurve"><string name="filename" value="spline.txt"/></shape></scene>)");
    MitsubaImportOptions options;
    options.model = kModel;
    const MitsubaImport im = importMitsubaScene(xml, options);
    std::string text;
    for (const auto& [name, bytes] : im.files)
        if (name == "curves/spline.txt") text = bytes;
    const CurveSet set = parseTextCurves(text, "spline.txt");
    ASSERT_EQ(set.curves.size(), 1u);
    const Curve& c = set.curves[0];
    ASSERT_EQ(c.points.size(), 9u);
    for (size_t k = 0; k < c.points.size(); ++k) {
        EXPECT_NEAR(c.points[k].x, 1 + k / 8.0, 1e-6);
        EXPECT_NEAR(c.radii[k], 2 + k / 8.0, 1e-6);
    }
    EXPECT_FALSE(im.notes.empty());  // the polyline is said
}

TEST_F(MitsubaTest, ImportExportImportIsTheIdentity) {
    writeFileAtomic(path("env.exr"),
                    encodeExr(weft::testing::constantImage(8, 4, Rgb(0.5)), "env.exr"));
    write("mesh.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n");
    write("knit.txt", "0 0 0 0.1\n1 0.2 0 0.1\n2 0 0.1 0.2\n\n0 1 0 0.1\n1 1 0 0.1\n");
    write("map.json", R"({"wool": {"model": ")" + kModel +
                          R"(", "plies": 3, "ply_twist": 0.3, "mode": "fiber"}})");
    const std::string xml = write("full.xml", R"(<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="65"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <string name="fov_axis" value="smaller"/>
        <transform name="to_world"><lookat origin="1, 2, 3" target="0, 0.5, 0" up="0, 1, 0"/></transform>
        <sampler type="ldsampler"><integer name="sample_count" value="16"/><integer name="seed" value="7"/></sampler>
        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="48"/><rfilter type="box"/></film>
    </sensor>
    <emitter type="envmap">
        <string name="filename" value="env.exr"/>
        <float name="scale" value="2"/>
        <transform name="to_world"><rotate y="1" angle="30"/></transform>
    </emitter>
    <emitter type="constant"><rgb name="radiance" value="0.1, 0.2, 0.3"/></emitter>
    <emitter type="point">
        <transform name="to_world"><translate value="1, 5, -2"/></transform>
        <rgb name="intensity" value="10, 20, 30"/>
    </emitter>
    <emitter type="directional">
        <vector name="direction" value="0, -1, 1"/>
        <spectrum name="irradiance" value="3"/>
    </emitter>
    <bsdf type="twosided" id="wall"><bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.4, 0.6"/></bsdf></bsdf>
    <shape type="obj">
        <string name="filename" value="mesh.obj"/>
        <transform name="to_world"><rotate x="1" angle="90"/><translate value="0, -1, 0"/></transform>
        <ref id="wall"/>
    </shape>
    <shape type="linearcurve">
        <string name="filename" value="knit.txt"/>
        <transform name="to_world"><scale value="2"/></transform>
        <bsdf type="diffuse" id="wool"/>
    </shape>
</scene>)");
    MitsubaImportOptions options;
    options.mapping = path("map.json");
    const MitsubaImport first = importMitsubaScene(xml, options);
    {
        auto files = first.files;
        files.push_back({"scene.json", first.scene.dump(2)});
        writeSceneFolder(files, path("weft1"));
    }
    const MitsubaExport exported = exportMitsubaScene(loadScene(path("weft1/scene.json")), false);
    writeSceneFolder(exported.files, path("mitsuba"));
    const MitsubaImport second = importMitsubaScene(path("mitsuba/scene.xml"), {});
    expectSameScene(second.scene, first.scene);
    const std::map<std::string, std::string> a(first.files.begin(), first.files.end()),
        b(second.files.begin(), second.files.end());
    ASSERT_EQ(a.size(), b.size());
    for (const auto& [name, bytes] : a) {
        ASSERT_TRUE(b.count(name)) << name;
        EXPECT_EQ(b.at(name), bytes) << name;
    }
    // What the first import read: the depth, the sampler, the mapping, the moved mesh.
    EXPECT_EQ(first.scene["render"]["max_depth"], 64);
    EXPECT_EQ(first.scene["render"]["sampler"], "sobol");
    EXPECT_EQ(first.scene["render"]["seed"], 7);
    EXPECT_EQ(first.scene["yarns"][0]["plies"], 3);
    EXPECT_EQ(first.scene["yarns"][0]["mode"], "fiber");
    EXPECT_NEAR(first.scene["lights"][0]["rotate_deg"].get<double>(), 30, 1e-9);
    EXPECT_EQ(first.scene["lights"][2],
              json({{"type", "point"}, {"position", {1, 5, -2}}, {"intensity", {10, 20, 30}}}));
    EXPECT_EQ(
        first.scene["lights"][3],
        json({{"type", "directional"}, {"direction", {0, -1, 1}}, {"irradiance", {3, 3, 3}}}));
    EXPECT_EQ(first.scene["objects"][0]["material"]["reflectance"], json({0.2, 0.4, 0.6}));
    const CurveSet knit = readCurves(path("weft1/curves/knit.txt"));
    EXPECT_NEAR(knit.curves[0].points[1].x, 2, 1e-6);  // scaled by to_world
    EXPECT_NEAR(knit.curves[0].radii[2], 0.4, 1e-6);
}

// PLY meshes: copied as they are, or moved by to_world into an OBJ of their
// own; either way weft reads the same triangles (placed by to_world).
TEST_F(MitsubaTest, PlyMeshesImportCopiedOrMoved) {
    write("tri.ply",
          "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
          "property float z\nelement face 1\nproperty list uchar uint vertex_indices\n"
          "end_header\n0 0 0\n1 0 0\n0 0 1\n3 0 1 2\n");
    const std::string xml = write("ply.xml", R"(<scene version="3.0.0">
    <sensor type="perspective"><float name="fov" value="30"/></sensor>
    <shape type="ply"><string name="filename" value="tri.ply"/><bsdf type="diffuse"/></shape>
    <shape type="ply">
        <string name="filename" value="tri.ply"/>
        <transform name="to_world"><translate value="0, -1, 0"/></transform>
        <bsdf type="diffuse"/>
    </shape>
</scene>)");
    MitsubaImportOptions options;
    options.model = kModel;
    const MitsubaImport im = importMitsubaScene(xml, options);
    {
        auto files = im.files;
        files.push_back({"scene.json", im.scene.dump(2)});
        writeSceneFolder(files, path("weft"));
    }
    const SceneDesc scene = loadScene(path("weft/scene.json"));
    ASSERT_EQ(scene.objects.size(), 2u);
    EXPECT_EQ(fs::path(scene.objects[0].file).extension(), ".ply");
    EXPECT_EQ(fs::path(scene.objects[1].file).extension(), ".obj");
    const Triangles copied = objectTriangles(scene.objects[0]);
    const Triangles moved = objectTriangles(scene.objects[1]);
    ASSERT_EQ(copied.vertices.size(), 3u);
    ASSERT_EQ(moved.vertices.size(), 3u);
    for (int i = 0; i < 3; ++i)
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(moved.vertices[i][c], copied.vertices[i][c] - (c == 1 ? 1 : 0), 1e-6);
    // A ply shape's file must be a .ply.
    write(
        "bad.xml",
        R"(<scene version="3.0.0"><sensor type="perspective"><float name="fov" value="30"/></sensor>
<shape type="ply"><string name="filename" value="yarn.txt"/><bsdf type="diffuse"/></shape></scene>)");
    expectInputError([&] { importMitsubaScene(path("bad.xml"), options); },
                     {"bad.xml:2", "ply shape's filename must end in .ply"});
}

TEST_F(MitsubaTest, FibersExportAsCurvesOfTheirRadius) {
    write("scene.json", R"({"camera": {"from": [0, 0, 1], "to": [0, 0, 0]},
        "yarns": [{"curves": "yarn.txt", "radius": 0.05, "plies": 2, "ply_twist": 0.2,
                   "model": ")" +
                            kModel + R"("}]})");
    const SceneDesc scene = loadScene(path("scene.json"));
    const MitsubaExport ex = exportMitsubaScene(scene, true);
    std::string text;
    for (const auto& [name, bytes] : ex.files)
        if (name.rfind("fibers/", 0) == 0) text = bytes;
    const CurveSet fibers = parseTextCurves(text, "fibers");
    // Every fiber of both plies, each within the yarn's radius of its axis.
    const YarnModel model = loadYarnModel(kModel);
    EXPECT_EQ(static_cast<int>(fibers.curves.size()), 2 * model.ply.fibers);
    for (const Curve& f : fibers.curves)
        for (const Vec3& p : f.points) EXPECT_LE(std::hypot(p.y, p.z), 0.05 + 1e-9);
}

TEST_F(MitsubaTest, WhatIsOutsideTheSubsetIsRefusedWithItsLineAndPath) {
    auto refuses = [&](const std::string& body, std::initializer_list<std::string> parts) {
        const std::string xml = write("bad.xml", body);
        MitsubaImportOptions options;
        options.model = kModel;
        expectInputError([&] { importMitsubaScene(xml, options); }, parts);
    };
    const std::string sensor =
        R"(<sensor type="perspective"><float name="fov" value="30"/></sensor>)";
    refuses("<scene version=\"3.0.0\">\n<sensor>\n</scene>", {"bad.xml:", "malformed XML"});
    refuses("<scene version=\"0.6.0\">" + sensor + "</scene>", {"bad.xml:1", "version \"0.6.0\""});
    refuses("<scene version=\"3.0.0\">\n" + sensor + "\n<shape type=\"cube\"/>\n</scene>",
            {"bad.xml:3", "scene/shape", "\"cube\""});
    refuses("<scene version=\"3.0.0\">" + sensor + "<emitter type=\"spot\"/></scene>",
            {"scene/emitter", "\"spot\""});
    refuses("<scene version=\"3.0.0\">" + sensor +
                "<emitter type=\"directional\"><vector name=\"direction\" value=\"0, 0, 0\"/>"
                "</emitter></scene>",
            {"scene/emitter", "direction cannot be 0"});
    refuses("<scene version=\"3.0.0\">" + sensor +
                "<emitter type=\"point\"><point name=\"position\" value=\"0, 0, 0\"/>"
                "<transform name=\"to_world\"><translate value=\"1, 0, 0\"/></transform>"
                "</emitter></scene>",
            {"scene/emitter", "position or to_world, not both"});
    refuses("<scene version=\"3.0.0\">" + sensor +
                "<shape type=\"linearcurve\"><string name=\"filename\" value=\"yarn.txt\"/>"
                "<ref id=\"nowhere\"/></shape></scene>",
            {"scene/shape/ref", "nowhere"});
    refuses("<scene version=\"3.0.0\">" + sensor +
                "<shape type=\"linearcurve\"><string name=\"filename\" value=\"$file\"/>"
                "</shape></scene>",
            {"\"$file\"", "<default name=\"file\">"});
    refuses(R"(<scene version="3.0.0"><sensor type="perspective"><float name="fov" value="30"/>
<float name="aperture_radius" value="0.1"/></sensor></scene>)",
            {"bad.xml:2", "scene/sensor/float[name=aperture_radius]", "it reads: fov"});
    refuses(R"(<scene version="3.0.0"><sensor type="perspective"><float name="fov" value="30"/>
<transform name="to_world"><scale x="-1"/></transform></sensor></scene>)",
            {"mirrors the image"});
    std::string deep;
    for (int i = 0; i < 20; ++i) deep += "<bsdf type=\"twosided\">";
    for (int i = 0; i < 20; ++i) deep += "</bsdf>";
    refuses("<scene version=\"3.0.0\">" + sensor + deep + "</scene>", {"nested deeper than 8"});
    refuses("<scene version=\"3.0.0\">" + sensor + "<texture type=\"bitmap\"/></scene>",
            {"scene/texture", "not read by weft"});
    refuses(
        "<scene version=\"3.0.0\"><shape type=\"linearcurve\"><string name=\"filename\" "
        "value=\"yarn.txt\"/></shape></scene>",
        {"no <sensor>"});
    write("short.txt", "0 0 0 1\n1 0 0 1\n2 0 0 1\n");
    refuses("<scene version=\"3.0.0\">" + sensor +
                "<shape type=\"bsplinecurve\"><string name=\"filename\" value=\"short.txt\"/>"
                "</shape></scene>",
            {"short.txt: curve 0", "4 points"});
    // No model for a bsdf: the mapping or --model is asked for.
    const std::string xml =
        write("nomodel.xml", "<scene version=\"3.0.0\">" + sensor +
                                 "<shape type=\"linearcurve\"><string name=\"filename\" "
                                 "value=\"yarn.txt\"/><bsdf type=\"diffuse\" id=\"silk\"/>"
                                 "</shape></scene>");
    expectInputError([&] { importMitsubaScene(xml, {}); }, {"bsdf \"silk\"", "--models"});
    // A mapping entry out of range names the bsdf id.
    write("badmap.json", R"({"silk": {"model": ")" + kModel + R"(", "plies": 40}})");
    MitsubaImportOptions mapped;
    mapped.mapping = path("badmap.json");
    expectInputError([&] { importMitsubaScene(xml, mapped); },
                     {"badmap.json: \"silk\"", "plies", "[1, 16]"});
}

}  // namespace
}  // namespace weft::render
