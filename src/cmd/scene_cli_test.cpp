// End-to-end tests of `weft scene`: the three kinds, a generated scene that
// `weft render` draws, and flag errors.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_test_util.h"
#include "weft/core/curves.h"
#include "weft/core/file.h"
#include "weft/core/image.h"
#include "weft/core/image_io.h"
#include "weft/core/npy.h"
#include "weft/render/curves.h"
#include "weft/render/scene_file.h"

namespace weft {
namespace {

using testing::expectUserError;
using testing::RunResult;

const std::string kFleece = std::string(WEFT_SOURCE_DIR) + "/tests/data/fleece-small.json";

class SceneCliTest : public testing::CliTestBase {};

TEST_F(SceneCliTest, GeneratedWeaveRenders) {
    RunResult r = run("scene weave --model " + kFleece +
                      " --size 2 --width 16 --height 16 --spp 1 --out weave");
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json summary = nlohmann::json::parse(r.out);
    EXPECT_EQ(summary.at("kind"), "weave");
    // 2 warp and 2 weft yarns in view, one more of each on either side to hide the ends.
    EXPECT_EQ(summary.at("yarns"), 8);
    EXPECT_EQ(summary.at("scene"), "weave/scene.json");
    // The generated yarns touch with 1% clearance: no overlap, no warning.
    EXPECT_EQ(r.err, "");
    const nlohmann::json& overlap = summary.at("yarn_overlap").at(0);
    EXPECT_EQ(overlap.at("curves"), "weave/yarns.txt");
    EXPECT_EQ(overlap.at("overlap_fraction"), 0.0);
    EXPECT_GT(overlap.at("largest_radius_without_overlap").get<double>(), 0.01);
    EXPECT_LT(overlap.at("largest_radius_without_overlap").get<double>(), 0.0102);

    r = run("render weave/scene.json --mode neural --spp 1 --threads 2 --quiet --out img.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    const Image image = readImage(path("img.exr"));
    EXPECT_EQ(image.width, 16);
    EXPECT_EQ(image.height, 16);
    for (float v : image.pixels) ASSERT_TRUE(std::isfinite(v) && v >= 0);
    const nlohmann::json stats = nlohmann::json::parse(readFile(path("img.json")));
    EXPECT_EQ(stats.at("scene").at("curves"), 8);
    EXPECT_EQ(stats.at("non_finite_samples"), 0);
    EXPECT_EQ(stats.at("scene").at("tubes"), 8 * 3);  // neural mode: one tube per ply
}

// Issue 43, item 1: `weft scene curves FILE` frames a curve file whole; the
// scene renders; `weft curves points` writes the points that a per-point
// colour .npy follows, and the render takes that .npy as vertex colours.
TEST_F(SceneCliTest, YourOwnCurvesFramedColouredAndRendered) {
    const std::string knit = std::string(WEFT_CURVE_DATA_DIR) + "/knit-stockinette-tiny.bcc";
    RunResult r = run("scene curves " + testing::shellQuote(knit) + " --model " + kFleece +
                      " --view front --width 24 --height 16 --spp 1 --out mine");
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json summary = nlohmann::json::parse(r.out);
    EXPECT_EQ(summary.at("kind"), "curves");
    EXPECT_EQ(summary.at("yarns"), 22);
    EXPECT_EQ(summary.at("curve_file").at("radius_from"), "largest_without_overlap");
    EXPECT_EQ(summary.at("yarn_overlap").at(0).at("overlap_fraction"), 0.0);
    EXPECT_EQ(r.err, "");
    // The curves keep the file's basis and point order, scaled.
    const CurveSet original = readCurves(knit), written = readCurves(path("mine/yarns.bcc"));
    ASSERT_EQ(written.pointCount(), original.pointCount());
    const double scale = summary.at("curve_file").at("scale").get<double>();
    EXPECT_NEAR(written.curves[3].points[5].x, scale * original.curves[3].points[5].x, 1e-6);
    EXPECT_EQ(written.curves[0].basis, original.curves[0].basis);

    // --floor: one diffuse rectangle under the cloth, drawn with it.
    r = run("scene curves " + testing::shellQuote(knit) + " --model " + kFleece +
            " --floor --width 24 --height 16 --spp 1 --out floored");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out).at("objects"), 1);
    const nlohmann::json floored = nlohmann::json::parse(readFile(path("floored/scene.json")));
    EXPECT_EQ(floored.at("objects").at(0).at("type"), "rectangle");
    EXPECT_EQ(floored.at("objects").at(0).at("normal"), nlohmann::json({0.0, 1.0, 0.0}));
    r = run("render floored/scene.json --quiet --out floored.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(readFile(path("floored.json"))).at("scene").at("triangles"), 2);

    r = run("curves points " + testing::shellQuote(knit) + " --out points.npy");
    ASSERT_EQ(r.status, 0) << r.err;
    const NpyMatrix points = readNpyMatrix(path("points.npy"), 4, "");
    ASSERT_EQ(points.rows, original.pointCount());
    EXPECT_EQ(points(0, 0), 0.0);
    EXPECT_EQ(points(points.rows - 1, 0), 21.0);
    EXPECT_EQ(points(1, 1), original.curves[0].points[1].x);
    // Colours by height: red at the bottom of the cloth, white at the top.
    std::vector<double> colours;
    for (size_t i = 0; i < points.rows; ++i)
        colours.insert(colours.end(),
                       {1.0, points(i, 2) > 0 ? 1.0 : 0.0, points(i, 2) > 0 ? 1.0 : 0.0});
    writeNpy(path("mine/colours.npy"), colours.data(), {points.rows, 3});
    nlohmann::json scene = nlohmann::json::parse(readFile(path("mine/scene.json")));
    scene["yarns"][0]["vertex_colours"] = "colours.npy";
    writeFileAtomic(path("mine/dyed.json"), scene.dump());
    r = run("render mine/dyed.json --mode fiber --spp 1 --quiet --out dyed.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    // One row short: refused, naming both counts.
    writeNpy(path("mine/colours.npy"), colours.data(), {points.rows - 1, 3});
    expectUserError(run("render mine/dyed.json --mode fiber --spp 1 --out dyed.exr"),
                    {"colours.npy", std::to_string(points.rows - 1) + " colour rows",
                     std::to_string(points.rows) + " points"});

    expectUserError(run("scene curves --model " + kFleece + " --out x"), {"curve file"});
    expectUserError(
        run("scene knit " + testing::shellQuote(knit) + " --model " + kFleece + " --out x"),
        {"weft scene curves only"});
    expectUserError(run("scene curves " + testing::shellQuote(knit) + " --model " + kFleece +
                        " --size 3 --out x"),
                    {"--size"});
    expectUserError(run("scene curves " + testing::shellQuote(knit) + " --model " + kFleece +
                        " --view side --out x"),
                    {"--view", "side"});
    expectUserError(run("curves points " + testing::shellQuote(knit) + " --out p.txt"),
                    {"--out", ".npy"});
}

TEST_F(SceneCliTest, EveryKindWithDefaults) {
    for (const std::string kind : {"closeup", "weave", "knit"}) {
        const RunResult r = run("scene " + kind + " --model " + kFleece + " --out " + kind);
        ASSERT_EQ(r.status, 0) << r.err;
        const render::SceneDesc s = render::loadScene(path(kind + "/scene.json"));
        EXPECT_EQ(s.film.width, 512);
        EXPECT_EQ(s.film.height, 512);
        EXPECT_EQ(s.render.spp, 64);
        ASSERT_EQ(s.yarns.size(), 1u);
        EXPECT_EQ(*s.yarns[0].radius, 0.01);
        EXPECT_EQ(s.yarns[0].plies, 3);
        EXPECT_EQ(s.yarns[0].plyTwist, 0.3);
        EXPECT_TRUE(std::filesystem::path(s.yarns[0].model).is_absolute());
        ASSERT_EQ(s.lights.size(), 3u);
        EXPECT_STREQ(s.lights[0]->type(), "sky");
        const size_t curves = readCurves(s.yarns[0].curves).curves.size();
        // The close-up's one yarn; the 12 yarns (6 courses) in view of a patch plus
        // those around them that hide the ends.
        if (kind == "closeup") {
            EXPECT_EQ(curves, 1u);
        } else {
            EXPECT_GE(curves, kind == "weave" ? 12u : 6u);
        }
    }
    // Flags reach the scene.
    const RunResult r =
        run("scene knit --model " + kFleece +
            " --size 2 --radius 0.5 --plies 2 --ply-twist -1 --width 64 --height 32 --spp 3"
            " --out k2");
    ASSERT_EQ(r.status, 0) << r.err;
    const render::SceneDesc s = render::loadScene(path("k2/scene.json"));
    EXPECT_EQ(*s.yarns[0].radius, 0.5);
    EXPECT_EQ(s.yarns[0].plies, 2);
    EXPECT_EQ(s.yarns[0].plyTwist, -1);
    EXPECT_EQ(s.film.width, 64);
    EXPECT_EQ(s.film.height, 32);
    EXPECT_EQ(s.render.spp, 3);
    // The 2 courses in view, one more above and below, and any that hide the ends.
    EXPECT_GE(readCurves(s.yarns[0].curves).curves.size(), 4u);
}

TEST_F(SceneCliTest, TwoColoursMakeTwoYarnEntries) {
    const RunResult r = run("scene knit --model " + kFleece +
                            " --size 2 --colours 0.9,0.2,0.1 0.1,0.3,0.8 --stripe 1 --width 12 "
                            "--height 8 --spp 1 --out striped");
    ASSERT_EQ(r.status, 0) << r.err;
    // Written, but said at once: neural mode will refuse it (issue 42).
    EXPECT_NE(r.err.find("warning: --colours: " + kFleece + " is fitted for one colour"),
              std::string::npos)
        << r.err;
    const nlohmann::json summary = nlohmann::json::parse(r.out);
    EXPECT_EQ(summary.at("curves"), nlohmann::json({"striped/yarns-1.txt", "striped/yarns-2.txt"}));
    EXPECT_EQ(summary.at("colours"), nlohmann::json({{0.9, 0.2, 0.1}, {0.1, 0.3, 0.8}}));
    EXPECT_EQ(summary.at("yarn_overlap").size(), 2u);
    const render::SceneDesc s = render::loadScene(path("striped/scene.json"));
    ASSERT_EQ(s.yarns.size(), 2u);
    EXPECT_EQ(*s.yarns[1].colour, Rgb(0.1, 0.3, 0.8));
    // Fiber mode colours the fibers of any model; neural mode needs a
    // colour-conditioned model and names the yarn entry.
    const RunResult fiber =
        run("render striped/scene.json --mode fiber --threads 2 --quiet --out f.exr");
    EXPECT_EQ(fiber.status, 0) << fiber.err;
    expectUserError(run("render striped/scene.json --mode neural --quiet --out n.exr"),
                    {"yarns[0].colour", "--colour-range"});
    // Space-dyed: one entry with a colour per point, rendered in fiber mode
    // with the two colours and the steps between them as materials.
    const RunResult dyed = run("scene closeup --model " + kFleece +
                               " --colours 0.9,0.2,0.1 0.1,0.3,0.8 --dye-length 3 --width 12 "
                               "--height 8 --spp 1 --out dyed");
    ASSERT_EQ(dyed.status, 0) << dyed.err;
    EXPECT_EQ(nlohmann::json::parse(dyed.out).at("vertex_colours"),
              nlohmann::json({"dyed/colours.txt"}));
    ASSERT_EQ(run("render dyed/scene.json --mode fiber --threads 2 --quiet --out d.exr").status, 0);
    const int64_t materials =
        nlohmann::json::parse(readFile(path("d.json"))).at("scene").at("materials").get<int64_t>();
    EXPECT_GE(materials, 2);
    EXPECT_LE(materials, 17);  // the two colours and at most 15 steps between them
    expectUserError(run("scene knit --model " + kFleece +
                        " --colours 0,0,0 1,1,1 --dye-length 3 --stripe 2 --out o"),
                    {"--stripe", "--dye-length"});
    // One colour: one entry in yarns.txt.
    ASSERT_EQ(
        run("scene weave --model " + kFleece + " --size 2 --colours 0.5,0.5,0.5 --out grey").status,
        0);
    EXPECT_EQ(*render::loadScene(path("grey/scene.json")).yarns.at(0).colour, Rgb(0.5));
}

// --appearance: the colours the yarns should look (docs/colour.md), written as
// the entries' "appearance", or as the C_TT that gives them along a
// space-dyed yarn; refused without a colour model or out of reach.
TEST_F(SceneCliTest, AppearanceColoursTheYarnsByHowTheyLook) {
    const std::string model = std::string(WEFT_SOURCE_DIR) + "/tests/data/fleece-colour-small.json";
    const std::string flags = " --width 12 --height 8 --spp 1";
    const RunResult one =
        run("scene closeup --model " + model + " --appearance '#a0704a'" + flags + " --out one");
    ASSERT_EQ(one.status, 0) << one.err;
    EXPECT_EQ(one.err, "");
    const render::SceneDesc s = render::loadScene(path("one/scene.json"));
    ASSERT_TRUE(s.yarns.at(0).appearance);
    EXPECT_EQ(*s.yarns[0].appearance, Rgb(0xa0 / 255.0, 0x70 / 255.0, 0x4a / 255.0));
    EXPECT_FALSE(s.yarns[0].colour);

    const RunResult dyed =
        run("scene closeup --model " + model +
            " --appearance '#a0704a' 0.3,0.4,0.5 --dye-length 3" + flags + " --out dyed");
    ASSERT_EQ(dyed.status, 0) << dyed.err;
    const RunResult probe = run("yarn appearance --model " + model + " --appearance '#a0704a'");
    ASSERT_EQ(probe.status, 0) << probe.err;
    const nlohmann::json cTT = nlohmann::json::parse(probe.out).at("c_tt");
    CurveSet points = readCurves(path("dyed/yarns.txt"));
    render::readVertexColours(path("dyed/colours.txt"), &points);
    bool found = false;
    for (const Rgb& c : points.curves.at(0).colours)
        found = found || (std::fabs(c.r - cTT[0].get<double>()) < 1e-6 &&
                          std::fabs(c.g - cTT[1].get<double>()) < 1e-6 &&
                          std::fabs(c.b - cTT[2].get<double>()) < 1e-6);
    EXPECT_TRUE(found) << "no point of the space-dyed yarn has the C_TT of #a0704a";

    expectUserError(run("scene closeup --model " + kFleece + " --appearance 0.5,0.4,0.3 --out o"),
                    {"--appearance", "fitted for one colour"});
    expectUserError(run("scene closeup --model " + model + " --appearance 1,1,1 --out o"),
                    {"--appearance", "out of reach"});
    expectUserError(run("scene closeup --model " + model +
                        " --appearance 0.5,0.4,0.3 --colours 0.5,0.5,0.5 --out o"),
                    {"--colours and --appearance", "not both"});
    expectUserError(run("scene closeup --model " + model + " --appearance '#12345' --out o"),
                    {"--appearance", "#rrggbb"});
}

// A family model's yarn (docs/family.md): the scene's entries carry it in
// "yarn" and render; a family without --yarn, --yarn with a model of one
// yarn and a yarn outside the box are refused.
TEST_F(SceneCliTest, FamilyYarnScenes) {
    const std::string family = std::string(WEFT_SOURCE_DIR) + "/models/family.json";
    const std::string yarn = R"('{"fibers": 250, "density": 0.38, "twist": 0.28, "beta_r_deg": 2,
        "beta_tt_deg": 12, "gamma_tt_deg": 21, "c_r": [0.2, 0.3, 0.4]}')";
    RunResult r = run("scene closeup --model " + family + " --yarn " + yarn +
                      " --colours 0.8,0.5,0.35 --width 16 --height 16 --spp 1 --out c");
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json scene = nlohmann::json::parse(readFile(path("c/scene.json")));
    const nlohmann::json& entry = scene.at("yarns").at(0);
    EXPECT_EQ(entry.at("yarn").at("fibers"), 250);
    EXPECT_EQ(entry.at("yarn").at("c_r"), nlohmann::json({0.2, 0.3, 0.4}));
    r = run("render c/scene.json --spp 1 --threads 2 --quiet --out c.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    expectUserError(run("scene closeup --model " + family + " --out d"),
                    {"--model", "family model", "--yarn"});
    expectUserError(run("scene closeup --model " + kFleece + " --yarn " + yarn + " --out d"),
                    {"--yarn", "model of one yarn"});
    expectUserError(run("scene closeup --model " + family + R"( --yarn '{"fibers": 100,
        "density": 0.3, "twist": 0.1, "beta_r_deg": 2, "beta_tt_deg": 12, "gamma_tt_deg": 21,
        "c_r": [0.2, 0.3, 0.4]}' --out d)"),
                    {"--yarn", "fibers", "100", "[200, 600]"});
    EXPECT_FALSE(std::filesystem::exists(path("d")));
}

// Issue 46: a Mitsuba 3 scene in, rendered, and out again (docs/mitsuba.md).
TEST_F(SceneCliTest, MitsubaSceneImportsRendersAndExports) {
    writeFileAtomic(path("ply.txt"), "-1 0 0 0.3\n1 0 0 0.3\n");
    writeFileAtomic(path("paper.xml"), R"(<scene version="3.0.0">
  <default name="spp" value="2"/>
  <integrator type="path"><integer name="max_depth" value="-1"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="30"/>
    <transform name="to_world"><lookat origin="0, 0, 8" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
  </sensor>
  <shape type="sphere"><point name="center" value="3, 4, 5"/><float name="radius" value="0.5"/>
    <emitter type="area"><rgb name="radiance" value="20, 20, 20"/></emitter></shape>
  <shape type="linearcurve"><string name="filename" value="ply.txt"/>
    <bsdf type="diffuse" id="ply"/></shape>
</scene>)");
    RunResult r =
        run("scene import paper.xml --model " + kFleece + " --define spp=1 --out imported");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out).at("yarns"), 1);
    // The Gaussian pixel filter Mitsuba would use is said, not skipped.
    EXPECT_NE(r.err.find("weft: note: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("box"), std::string::npos) << r.err;
    r = run("render imported/scene.json --quiet --out img.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(readFile(path("img.json"))).at("spp"), 1);

    r = run("scene export imported/scene.json --mitsuba mitsuba --fibers");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_TRUE(std::filesystem::exists(path("mitsuba/scene.xml")));
    EXPECT_TRUE(std::filesystem::exists(path("mitsuba/weft-models.json")));
    r = run("scene export imported/scene.json --mitsuba mitsuba");
    ASSERT_EQ(r.status, 0) << r.err;
    r = run("scene import mitsuba/scene.xml --out again");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(readFile(path("again/curves/ply.txt")), readFile(path("imported/curves/ply.txt")));

    expectUserError(run("scene import missing.xml --out o"), {"missing.xml"});
    expectUserError(run("scene import paper.xml --out o"), {"bsdf \"ply\"", "--model"});
    expectUserError(run("scene import paper.xml --model " + kFleece + " --define spp --out o"),
                    {"--define spp", "NAME=VALUE"});
    expectUserError(run("scene import --out o"), {"weft scene import SCENE.xml"});
    expectUserError(run("scene export imported/scene.json"), {"--mitsuba"});
    expectUserError(run("scene knit --model " + kFleece + " --fibers --out o"),
                    {"--fibers", "import or export"});
    // Never over an input; nor over a folder holding something else.
    expectUserError(run("scene export imported/scene.json --mitsuba imported"), {"--mitsuba"});
    std::filesystem::create_directory(path("busy"));
    writeFileAtomic(path("busy/notes.txt"), "keep");
    expectUserError(run("scene import paper.xml --model " + kFleece + " --out busy"),
                    {"busy", "notes.txt"});
    EXPECT_EQ(readFile(path("busy/notes.txt")), "keep");
}

TEST_F(SceneCliTest, BadInputIsNamed) {
    const std::string m = " --model " + kFleece;
    expectUserError(run("scene twill" + m + " --out o"), {"twill", "closeup, weave, knit"});
    expectUserError(run("scene weave" + m + " --size 0 --out o"), {"--size 0", "[1, 100]"});
    expectUserError(run("scene knit" + m + " --size 101 --out o"), {"--size 101", "[1, 100]"});
    expectUserError(run("scene closeup" + m + " --size 3 --out o"), {"--size", "weave and knit"});
    expectUserError(run("scene weave" + m + " --radius 0 --out o"), {"--radius 0", "1e-06"});
    expectUserError(run("scene weave" + m + " --plies 17 --out o"), {"--plies 17", "[1, 16]"});
    expectUserError(run("scene weave" + m + " --ply-twist 200 --out o"),
                    {"--ply-twist 200", "[-100, 100]"});
    expectUserError(run("scene weave" + m + " --width 0 --out o"), {"--width 0", "[1, 16384]"});
    expectUserError(run("scene weave" + m + " --height 16385 --out o"), {"--height 16385"});
    expectUserError(run("scene weave" + m + " --spp 0 --out o"), {"--spp 0", "[1, 1048576]"});
    expectUserError(run("scene weave --model missing.json --out o"), {"--model", "missing.json"});
    expectUserError(run("scene knit" + m + " --colours 0.5,0.5 --out o"), {"--colours", "R,G,B"});
    expectUserError(run("scene knit" + m + " --colours 0.5,0.5,1.5 --out o"),
                    {"--colours", "[0, 1]"});
    expectUserError(run("scene knit" + m + " --colours 0,0,0 1,1,1 0.5,0.5,0.5 --out o"),
                    {"--colours"});
    expectUserError(run("scene closeup" + m + " --colours 0,0,0 1,1,1 --out o"),
                    {"--colours", "one colour", "--dye-length"});
    expectUserError(run("scene closeup" + m + " --colours 0,0,0 1,1,1 --dye-length 0.1 --out o"),
                    {"--dye-length 0.1", "[0.5, 10000]"});
    // Given means checked, 0 included (issue 41: 0 was taken for "not given").
    expectUserError(run("scene knit" + m + " --colours 0,0,0 1,1,1 --dye-length 0 --out o"),
                    {"--dye-length 0", "[0.5, 10000]"});
    // Issue 41: films a patch cannot fill searched for an extension forever.
    expectUserError(run("scene weave" + m + " --width 1 --height 512 --size 2 --out o"),
                    {"--width 1 --height 512", "at most 10"});
    expectUserError(run("scene knit" + m + " --width 1 --height 16 --out o"),
                    {"--width 1 --height 16", "a knit allows at most 10"});
    expectUserError(run("scene weave" + m + " --width 16384 --height 1 --out o"),
                    {"--width 16384 --height 1", "at most 100"});
    expectUserError(run("scene knit" + m + " --stripe 2 --out o"), {"--stripe", "two --colours"});
    expectUserError(run("scene knit" + m + " --colours 0,0,0 1,1,1 --stripe 0 --out o"),
                    {"--stripe 0", "[1, 100]"});
    expectUserError(run("scene weave" + m + " --envmap sky.png --out o"), {"--envmap", "sky.png"});
    expectUserError(run("scene weave" + m + " --envmap sky.exr --out o"), {"--envmap", "sky.exr"});
    // CLI11's own errors (a missing flag, not a number) exit with 2 as well.
    EXPECT_EQ(run("scene weave --out o").status, 2);
    EXPECT_EQ(run("scene weave" + m + " --size two --out o").status, 2);
    EXPECT_FALSE(std::filesystem::exists(path("o")));

    // An output directory holding anything but an earlier scene is left alone.
    std::filesystem::create_directory(path("busy"));
    writeFileAtomic(path("busy/notes.txt"), "keep me");
    expectUserError(run("scene weave" + m + " --out busy"), {"busy", "notes.txt"});
    EXPECT_EQ(readFile(path("busy/notes.txt")), "keep me");
    EXPECT_EQ(testing::CliTestBase::listing(), (std::vector<std::string>{"busy"}));
}

}  // namespace
}  // namespace weft
