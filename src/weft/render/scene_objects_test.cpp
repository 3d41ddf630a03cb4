// Tests of a scene's objects (issue 43, item 2): reading them, the OBJ
// reader, the rectangle's triangles, and in renders: a diffuse floor under a
// constant sky (the white-furnace case: every path that leaves it escapes,
// so its radiance is its reflectance), and objects that occlude yarns in
// both drawing modes.
#include "weft/render/scene_objects.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "weft/core/file.h"
#include "weft/core/math.h"
#include "weft/core/test_util.h"
#include "weft/render/renderer.h"
#include "weft/render/scene.h"
#include "weft/render/scene_file.h"

namespace weft::render {
namespace {

using weft::testing::expectInputError;

const std::string kFleece = std::string(WEFT_SOURCE_DIR) + "/tests/data/fleece-small.json";

TEST(ObjTriangles, FansNegativeIndicesAndSlashFormsAreRead) {
    const Triangles t = parseObjTriangles(
        "# a quad and a triangle\n"
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
        "vt 0 0\nvn 0 0 1\n"
        "f 1/1/1 2/1/1 3//1 4\n"
        "v 2 2 2\n"
        "f -1 -2 -3\n"
        "o ignored\ns off\n",
        "quad.obj");
    ASSERT_EQ(t.vertices.size(), 5u);
    ASSERT_EQ(t.indices.size(), 3u);
    EXPECT_EQ(t.indices[0], (std::array<uint32_t, 3>{0, 1, 2}));
    EXPECT_EQ(t.indices[1], (std::array<uint32_t, 3>{0, 2, 3}));
    EXPECT_EQ(t.indices[2], (std::array<uint32_t, 3>{4, 3, 2}));
}

TEST(ObjTriangles, BadLinesAreNamed) {
    expectInputError([] { parseObjTriangles("v 0 0\n", "a.obj"); }, {"a.obj:1", "'v x y z'"});
    expectInputError([] { parseObjTriangles("v 0 0 nan\n", "a.obj"); },
                     {"a.obj:1", "out of range"});
    expectInputError([] { parseObjTriangles("v 0 0 0\nv 1 0 0\nf 1 2\n", "a.obj"); },
                     {"a.obj:3", "at least 3"});
    expectInputError([] { parseObjTriangles("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "a.obj"); },
                     {"a.obj:4", "index 4", "3 vertices"});
    expectInputError([] { parseObjTriangles("v 0 0 0\nf 0 1 1\n", "a.obj"); }, {"a.obj:2", "'0'"});
    expectInputError([] { parseObjTriangles("v 0 0 0\n", "a.obj"); }, {"a.obj", "no faces"});
}

// The PLY reader: one mesh (a quad and a triangle, as the OBJ test above) in
// ascii and in both binary byte orders, with properties and an element weft
// does not use, written here byte by byte from the format's description.
static_assert(std::endian::native == std::endian::little, "the PLY test writes host bytes");

template <typename T>
void putPly(std::string& out, T v, bool bigEndian) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof v);
    if (bigEndian) std::reverse(b, b + sizeof(T));
    out.append(b, sizeof(T));
}

const char* const kPlyHeaderBody =
    "comment a quad and a triangle\n"
    "element vertex 5\n"
    "property float x\nproperty double y\nproperty float z\nproperty uchar red\n"
    "element face 2\n"
    "property list uchar int vertex_indices\nproperty list ushort float texcoord\n"
    "element edge 1\nproperty list int uint vertex_pair\n"
    "element nothing 1000000000000\n"
    "end_header\n";
const double kPlyVertices[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 2, 2}};

std::string binaryPly(bool bigEndian, double firstX = 0) {
    std::string out = std::string("ply\nformat binary_") + (bigEndian ? "big" : "little") +
                      "_endian 1.0\n" + kPlyHeaderBody;
    for (int i = 0; i < 5; ++i) {
        putPly(out, static_cast<float>(i == 0 ? firstX : kPlyVertices[i][0]), bigEndian);
        putPly(out, kPlyVertices[i][1], bigEndian);
        putPly(out, static_cast<float>(kPlyVertices[i][2]), bigEndian);
        putPly(out, static_cast<uint8_t>(200), bigEndian);
    }
    const std::vector<std::vector<int32_t>> faces = {{0, 1, 2, 3}, {4, 3, 2}};
    for (const auto& f : faces) {
        putPly(out, static_cast<uint8_t>(f.size()), bigEndian);
        for (int32_t v : f) putPly(out, v, bigEndian);
        putPly(out, static_cast<uint16_t>(2), bigEndian);
        putPly(out, 0.5f, bigEndian);
        putPly(out, 0.25f, bigEndian);
    }
    putPly(out, int32_t{2}, bigEndian);
    putPly(out, uint32_t{0}, bigEndian);
    putPly(out, uint32_t{1}, bigEndian);
    return out;
}

const std::string kAsciiPly = std::string("ply\nformat ascii 1.0\n") + kPlyHeaderBody +
                              "0 0 0 200\n1 0 0 200\n1 1 0 200\n0 1 0 200\n2 2 2 200\n"
                              "4 0 1 2 3 2 0.5 0.25\n3 4 3 2 2 0.5 0.25\n"
                              "2 0 1\n";

TEST(PlyTriangles, AsciiAndBothByteOrdersGiveTheSameTriangles) {
    for (const std::string& bytes : {kAsciiPly, binaryPly(false), binaryPly(true)}) {
        SCOPED_TRACE(bytes.substr(0, 30));
        const Triangles t = parsePlyTriangles(bytes, "m.ply");
        ASSERT_EQ(t.vertices.size(), 5u);
        for (int i = 0; i < 5; ++i)
            EXPECT_EQ(t.vertices[i],
                      Vec3(kPlyVertices[i][0], kPlyVertices[i][1], kPlyVertices[i][2]));
        ASSERT_EQ(t.indices.size(), 3u);
        EXPECT_EQ(t.indices[0], (std::array<uint32_t, 3>{0, 1, 2}));
        EXPECT_EQ(t.indices[1], (std::array<uint32_t, 3>{0, 2, 3}));
        EXPECT_EQ(t.indices[2], (std::array<uint32_t, 3>{4, 3, 2}));
    }
}

TEST(PlyTriangles, BadFilesAreNamedWithWhereTheyGoWrong) {
    const auto rejects = [](const std::string& bytes, std::initializer_list<std::string> parts) {
        expectInputError([&] { parsePlyTriangles(bytes, "m.ply"); }, parts);
    };
    const auto replaced = [](std::string s, const std::string& from, const std::string& to) {
        return s.replace(s.find(from), from.size(), to);
    };
    rejects("plx\n", {"m.ply:1", "not a PLY file"});
    rejects(replaced(kAsciiPly, "ascii", "binary_middle_endian"),
            {"m.ply:2", "binary_middle_endian", "allowed: ascii"});
    rejects(replaced(kAsciiPly, "end_header", "end_head"), {"m.ply:15", "unknown header line"});
    rejects("ply\nformat ascii 1.0\nelement vertex 1\n", {"m.ply", "no end_header"});
    rejects("ply\nformat ascii 1.0\nproperty float x\nend_header\n",
            {"m.ply:3", "a property before any element"});
    rejects(replaced(kAsciiPly, "list uchar int", "list float int"),
            {"m.ply:10", "count type must be an integer"});
    rejects(replaced(kAsciiPly, "property float x", "property float w"),
            {"m.ply", "no property x"});
    rejects(replaced(kAsciiPly, "1 1 0 200", "1 abc 0 200"),
            {"m.ply:18", "element vertex 2.y", "expected a number", "abc"});
    rejects(replaced(kAsciiPly, "3 4 3 2", "3 4 3 7"),
            {"m.ply", "vertex index 7 is out of range: 5 vertices"});
    rejects(replaced(kAsciiPly, "3 4 3 2", "2 4 3"), {"element face 1", "at least 3 vertices"});
    const std::string binary = binaryPly(false);
    rejects(binary.substr(0, binary.size() - 3),
            {"m.ply", "element edge 0.vertex_pair", "the file ends before it"});
    rejects(binaryPly(true, std::numeric_limits<double>::quiet_NaN()),
            {"m.ply", "element vertex 0", "vertex coordinate out of range"});
    rejects(replaced(kAsciiPly, "element face 2", "element face 0"), {"m.ply", "no faces"});
}

TEST(SceneObjects, RectangleIsTwoTrianglesOfItsSizeAroundItsCentre) {
    ObjectDesc o;
    o.center = {1, 2, 3};
    o.normal = {0, 1, 0};
    o.size = {4, 6};
    const Triangles t = objectTriangles(o);
    ASSERT_EQ(t.indices.size(), 2u);
    for (const Vec3& p : t.vertices) {
        EXPECT_NEAR(p.y, 2, 1e-12);
        EXPECT_NEAR(std::abs(p.x - 1), 2, 1e-12);  // width along x
        EXPECT_NEAR(std::abs(p.z - 3), 3, 1e-12);  // height along z
    }
    // Both triangles face the same way.
    for (const auto& tri : t.indices) {
        const Vec3 n =
            cross(t.vertices[tri[1]] - t.vertices[tri[0]], t.vertices[tri[2]] - t.vertices[tri[0]]);
        EXPECT_GT(std::abs(n.y), 0);
    }
}

class SceneObjectsTest : public weft::testing::TempDirTest {
  protected:
    std::string scene(
        const std::string& objects, const std::string& yarns = "",
        const std::string& lights = R"({"type": "constant", "radiance": [1, 1, 1]})") {
        writeFileAtomic(path("yarn.txt"), "-0.2 0 0\n0 0.01 0\n0.2 0 0\n");
        return R"({"camera": {"from": [0, 0.6, 1], "to": [0, 0, 0], "fov_deg": 10},
                   "film": {"width": 12, "height": 12}, "render": {"spp": 16, "seed": 4},
                   "lights": [)" +
               lights + R"(], "yarns": [)" + yarns + R"(], "objects": [)" + objects + "]}";
    }
    RenderResult render(const std::string& text, const std::string& mode, bool nee = true,
                        int spp = 16) {
        const SceneDesc desc = parseSceneText(text, path("scene.json"), dir_.string());
        SceneOptions so;
        so.mode = mode;
        const Scene s(desc, so);
        RenderOptions o;
        o.spp = spp;
        o.seed = 4;
        o.quiet = true;
        o.nextEventEstimation = nee;
        return weft::render::render(s, o);
    }
};

const std::string kYarn = R"({"curves": "yarn.txt", "radius": 0.03, "plies": 3, "ply_twist": 0.3,
                              "model": ")" +
                          kFleece + R"("})";

// The white-furnace case of a surface: under a constant sky of radiance 1,
// a diffuse floor that sees nothing but the sky returns its reflectance.
// BSDF sampling alone is exact (every path escapes with weight R); with
// next-event estimation it is right in expectation.
TEST_F(SceneObjectsTest, ADiffuseFloorUnderAConstantSkyReturnsItsReflectance) {
    const std::string floor =
        R"({"type": "rectangle", "center": [0, -0.05, 0], "size": [1000, 1000],
        "material": {"type": "diffuse", "reflectance": [0.2, 0.5, 0.9]}})";
    const RenderResult exact = render(scene(floor), "neural", false);
    EXPECT_EQ(exact.stats.scene.objects, 1);
    EXPECT_EQ(exact.stats.scene.triangles, 2);
    for (size_t i = 0; i < exact.image.pixels.size(); ++i)
        ASSERT_NEAR(exact.image.pixels[i], (i % 3 == 0 ? 0.2 : i % 3 == 1 ? 0.5 : 0.9), 1e-6) << i;
    const RenderResult mis = render(scene(floor), "neural", true, 256);
    Rgb mean;
    for (size_t i = 0; i < mis.image.pixels.size(); ++i) mean[i % 3] += mis.image.pixels[i] / 144.0;
    EXPECT_NEAR(mean.r, 0.2, 0.004);
    EXPECT_NEAR(mean.g, 0.5, 0.01);
    EXPECT_NEAR(mean.b, 0.9, 0.018);
}

// An object between the camera and a yarn hides it in every drawing mode:
// the image is the one without the yarn, to the bit (the same paths). Without
// the object the yarn shows.
TEST_F(SceneObjectsTest, ObjectsOccludeYarnsInEveryMode) {
    writeFileAtomic(path("screen.obj"),
                    "v -5 -5 0.5\nv 5 -5 0.5\nv 5 5 0.5\nv -5 5 0.5\nf 1 2 3 4\n");
    const std::string screens[] = {
        R"({"type": "rectangle", "center": [0, 0.3, 0.5], "normal": [0, 0.6, 1], "size": [10, 10],
            "material": {"type": "conductor", "colour": [0.9, 0.6, 0.3], "roughness": 0.5}})",
        R"({"type": "mesh", "file": "screen.obj", "scale": 1, "translate": [0, 0, 0.1]})"};
    for (const std::string& screen : screens)
        for (const std::string mode : {"neural", "fiber"}) {
            SCOPED_TRACE(mode + " " + screen.substr(0, 30));
            const RenderResult hidden = render(scene(screen, kYarn), mode);
            const RenderResult alone = render(scene(screen), mode);
            EXPECT_EQ(hidden.image.pixels, alone.image.pixels);
            const RenderResult seen = render(scene("", kYarn), mode);
            const RenderResult empty = render(scene(""), mode);
            EXPECT_NE(seen.image.pixels, empty.image.pixels);
        }
}

// A floor lights a yarn from below: the yarn above a white floor is brighter
// than above a black one (the floor takes part in transport, not just occlusion).
TEST_F(SceneObjectsTest, AFloorReflectsLightOntoTheYarn) {
    const auto floor = [](double r) {
        const std::string v = std::to_string(r);
        return R"({"type": "rectangle", "center": [0, -0.1, 0], "size": [10, 10],
                   "material": {"type": "diffuse", "reflectance": [)" +
               v + "," + v + "," + v + "]}}";
    };
    const std::string above =
        R"({"type": "sphere", "center": [0, 3, 0], "radius": 0.5, "radiance": [5, 5, 5]})";
    for (const std::string mode : {"neural", "fiber"}) {
        double sum[2] = {0, 0};
        for (int k = 0; k < 2; ++k) {
            const RenderResult r =
                render(scene(floor(k == 0 ? 0.0 : 1.0), kYarn, above), mode, true, 32);
            for (float v : r.image.pixels) sum[k] += v;
        }
        EXPECT_GT(sum[1], 1.05 * sum[0]) << mode;
    }
}

// Direct light from a point light and from a sun on a diffuse floor against
// their formulas, L = (rho / pi) I cos(theta) / d^2 and L = (rho / pi) E
// cos(theta), each pixel the average of that over its footprint: no other
// light, so the paths that leave the floor add nothing and only the pixel
// position varies between samples. Both lights in one scene, picked by power,
// give the sum (the pick probability divides each delta sample).
TEST_F(SceneObjectsTest, PointAndDirectionalLightsOnADiffuseFloorFollowTheirFormulas) {
    const Rgb rho(0.2, 0.5, 0.9);
    const double floorY = -0.05;
    // Big enough to fill the view, small enough that the sun's power (pi R^2 E,
    // R the scene's radius) does not starve the point light of picks.
    const std::string floor =
        R"({"type": "rectangle", "center": [0, -0.05, 0], "size": [4, 4],
        "material": {"type": "diffuse", "reflectance": [0.2, 0.5, 0.9]}})";
    const Vec3 position(0.05, 0.45, -0.02);
    const Rgb intensity(3, 2, 1), irradiance(1, 2, 3);
    const Vec3 towardsSun = normalize(Vec3(-1, 2, -0.5));
    const std::string point = R"({"type": "point", "position": [0.05, 0.45, -0.02],
                                  "intensity": [3, 2, 1]})";
    const std::string sun =
        R"({"type": "directional", "direction": [1, -2, 0.5], "irradiance": [1, 2, 3]})";
    const auto pointRadiance = [&](const Vec3& p) {
        const Vec3 d = position - p;
        const double d2 = dot(d, d);
        return rho * intensity * ((d.y / std::sqrt(d2)) / (kPi * d2));
    };
    const auto sunRadiance = [&](const Vec3&) { return rho * irradiance * (towardsSun.y / kPi); };
    const auto parse = [&](const std::string& text) {
        return parseSceneText(text, path("scene.json"), dir_.string());
    };
    // The formula averaged over each pixel (8 x 8 film positions).
    const auto expected = [&](const Scene& s, auto&& radiance) {
        std::vector<Rgb> out;
        for (int y = 0; y < s.height(); ++y)
            for (int x = 0; x < s.width(); ++x) {
                Rgb sum(0.0);
                for (int j = 0; j < 8; ++j)
                    for (int i = 0; i < 8; ++i) {
                        Vec3 org, dir;
                        s.camera().ray(x + (i + 0.5) / 8, y + (j + 0.5) / 8, &org, &dir);
                        sum += radiance(org + dir * ((floorY - org.y) / dir.y));
                    }
                out.push_back(sum / 64.0);
            }
        return out;
    };
    std::vector<Rgb> truth[2];
    for (int k = 0; k < 2; ++k) {
        SCOPED_TRACE(k == 0 ? "point" : "directional");
        const Scene s(parse(scene(floor, "", k == 0 ? point : sun)));
        truth[k] = k == 0 ? expected(s, pointRadiance) : expected(s, sunRadiance);
        const RenderResult r = render(scene(floor, "", k == 0 ? point : sun), "neural", true, 64);
        for (size_t i = 0; i < r.image.pixels.size(); ++i) {
            const double want = truth[k][i / 3][static_cast<int>(i % 3)];
            ASSERT_NEAR(r.image.pixels[i], want, 0.01 * want) << i;
        }
    }
    // Both, picked by power: the sum, within the pick's noise (image means).
    std::string both = scene(floor, "", point + ", " + sun);
    both.replace(both.find("\"lights\""), 8, R"("light_sampler": "power", "lights")");
    const RenderResult r = render(both, "neural", true, 64);
    Rgb mean(0.0), want(0.0);
    for (size_t i = 0; i < r.image.pixels.size(); ++i) {
        mean[static_cast<int>(i % 3)] += r.image.pixels[i];
        want[static_cast<int>(i % 3)] +=
            truth[0][i / 3][static_cast<int>(i % 3)] + truth[1][i / 3][static_cast<int>(i % 3)];
    }
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean[c], want[c], 0.02 * want[c]) << c;
    // Without next-event estimation nothing would reach them: refused, not black.
    expectInputError([&] { render(scene(floor, "", point), "neural", false); },
                     {"lights[0]", "point or directional", "--no-nee"});
}

// A mesh object reads PLY as it reads OBJ: the same mesh in both formats
// renders the same image, to the bit.
TEST_F(SceneObjectsTest, PlyAndObjMeshesRenderTheSame) {
    writeFileAtomic(path("m.obj"),
                    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 2 2\nf 1 2 3 4\nf 5 4 3\n");
    writeFileAtomic(path("m.ply"), binaryPly(true));
    const auto mesh = [](const std::string& file) {
        return R"({"type": "mesh", "file": ")" + file +
               R"(", "scale": 0.2, "translate": [-0.1, -0.1, 0]})";
    };
    const RenderResult obj = render(scene(mesh("m.obj")), "neural");
    const RenderResult ply = render(scene(mesh("m.ply")), "neural");
    EXPECT_EQ(obj.stats.scene.triangles, 3);
    EXPECT_EQ(ply.image.pixels, obj.image.pixels);
    EXPECT_NE(obj.image.pixels, render(scene(""), "neural").image.pixels);  // the mesh shows
}

TEST_F(SceneObjectsTest, ObjectsAreValidatedAndWrittenBack) {
    const auto parse = [&](const std::string& objects) {
        return parseSceneText(scene(objects), path("scene.json"), dir_.string());
    };
    expectInputError([&] { parse(R"({"type": "sphere"})"); },
                     {"objects[0].type", "\"rectangle\", \"mesh\"", "sphere"});
    expectInputError([&] { parse(R"({"type": "rectangle"})"); },
                     {"objects[0]", "missing key \"center\""});
    expectInputError(
        [&] { parse(R"({"type": "rectangle", "center": [0,0,0], "normal": [0,0,0]})"); },
        {"objects[0].normal"});
    expectInputError([&] { parse(R"({"type": "rectangle", "center": [0,0,0], "file": "a.obj"})"); },
                     {"objects[0]", "file"});
    expectInputError([&] { parse(R"({"type": "mesh", "file": "a.stl"})"); },
                     {"objects[0].file", ".obj"});
    expectInputError(
        [&] {
            parse(
                R"({"type": "rectangle", "center": [0,0,0], "material": {"type": "diffuse", "reflectance": [0, 2, 0]}})");
        },
        {"objects[0].material.reflectance", "[0, 1]"});
    expectInputError(
        [&] {
            parse(
                R"({"type": "rectangle", "center": [0,0,0], "material": {"type": "conductor", "roughness": 0}})");
        },
        {"objects[0].material.roughness", "0.01"});
    expectInputError(
        [&] {
            parse(
                R"({"type": "rectangle", "center": [0,0,0], "material": {"type": "diffuse", "roughness": 0.5}})");
        },
        {"objects[0].material", "roughness"});
    // A missing mesh file: named when the scene is built.
    const SceneDesc missing = parse(R"({"type": "mesh", "file": "missing.obj"})");
    expectInputError([&] { Scene s(missing); }, {"objects[0]", "missing.obj"});
    // Round trip.
    const SceneDesc s =
        parse(R"({"type": "rectangle", "center": [1, 2, 3], "normal": [0, 2, 0], "size": [3, 4],
        "material": {"type": "conductor", "colour": [0.1, 0.2, 0.3], "roughness": 0.25}})");
    const SceneDesc again = parseScene(toJson(s), "again.json", dir_.string());
    ASSERT_EQ(again.objects.size(), 1u);
    EXPECT_EQ(toJson(again), toJson(s));
    EXPECT_EQ(again.objects[0].normal, (Vec3{0, 1, 0}));
    EXPECT_EQ(again.objects[0].material.roughness, 0.25);
}

}  // namespace
}  // namespace weft::render
