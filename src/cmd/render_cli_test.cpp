// End-to-end tests of `weft render`: outputs, statistics, budgets and input errors.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <utility>

#include "cli_test_util.h"
#include "weft/core/file.h"
#include "weft/core/image.h"
#include "weft/core/image_io.h"
#include "weft/eval/image_compare.h"

namespace weft {
namespace {

using testing::contains;
using testing::expectUserError;
using testing::RunResult;

const std::string kFleece = std::string(WEFT_SOURCE_DIR) + "/tests/data/fleece-small.json";

class RenderCliTest : public testing::CliTestBase {
  protected:
    void SetUp() override {
        CliTestBase::SetUp();
        writeFileAtomic(path("yarn.txt"), "-0.2 0 0\n0 0.01 0\n0.2 0 0\n");
        writeScene("scene.json", "");
    }
    void writeScene(const std::string& name, const std::string& extraYarnKey) {
        writeFileAtomic(path(name), R"({
            "camera": {"from": [0, 0, 1], "to": [0, 0, 0], "fov_deg": 8},
            "film": {"width": 16, "height": 12},
            "render": {"spp": 2, "seed": 1},
            "yarns": [{"curves": "yarn.txt", "radius": 0.03, "plies": 3, "ply_twist": 0.3,
                       "model": ")" + kFleece +
                                        "\"" + extraYarnKey + R"(}]
        })");
    }
};

TEST_F(RenderCliTest, WritesExrPngAndStatistics) {
    for (const std::string mode : {"neural", "fiber"}) {
        const RunResult r =
            run("render scene.json --mode " + mode + " --spp 2 --threads 2 --out " + mode + ".exr");
        ASSERT_EQ(r.status, 0) << r.err;
        const Image image = readImage(path(mode + ".exr"));
        EXPECT_EQ(image.width, 16);
        EXPECT_EQ(image.height, 12);
        for (float v : image.pixels) ASSERT_TRUE(std::isfinite(v));
        EXPECT_TRUE(std::filesystem::exists(path(mode + ".png")));
        const nlohmann::json stats = nlohmann::json::parse(readFile(path(mode + ".json")));
        EXPECT_EQ(stats.at("mode"), mode);
        EXPECT_EQ(stats.at("spp"), 2);
        EXPECT_GT(stats.at("rays_per_second").get<double>(), 0.0);
        EXPECT_GT(stats.at("peak_resident_bytes").get<int64_t>(), 0);
        EXPECT_GT(stats.at("scene").at("geometry_bvh_bytes").get<int64_t>(), 0);
        EXPECT_EQ(stats.at("scene").at("curves"), 1);
        EXPECT_EQ(stats.at("scene_hash").get<std::string>().size(), 16u);
        EXPECT_EQ(stats.at("non_finite_samples"), 0);
    }
    // Same seed, same image (files byte for byte), whatever the thread count.
    ASSERT_EQ(run("render scene.json --spp 2 --threads 1 --out again.exr").status, 0);
    EXPECT_EQ(readImage(path("again.exr")).pixels, readImage(path("neural.exr")).pixels);
}

// --fiber-seed is the scene's render.fiber_seed: the same image and scene
// hash as the scene file with it, other fibers than the default.
TEST_F(RenderCliTest, FiberSeedFlagIsTheScenesFiberSeed) {
    ASSERT_EQ(run("render scene.json --mode fiber --spp 1 --quiet --out f0.exr").status, 0);
    ASSERT_EQ(
        run("render scene.json --mode fiber --spp 1 --fiber-seed 7 --quiet --out f7.exr").status,
        0);
    nlohmann::json scene = nlohmann::json::parse(readFile(path("scene.json")));
    scene["render"]["fiber_seed"] = 7;
    writeFileAtomic(path("seeded.json"), scene.dump());
    ASSERT_EQ(run("render seeded.json --mode fiber --spp 1 --quiet --out s7.exr").status, 0);
    EXPECT_EQ(readImage(path("f7.exr")).pixels, readImage(path("s7.exr")).pixels);
    EXPECT_NE(readImage(path("f7.exr")).pixels, readImage(path("f0.exr")).pixels);
    const auto hash = [&](const std::string& name) {
        return nlohmann::json::parse(readFile(path(name))).at("scene_hash").get<std::string>();
    };
    EXPECT_EQ(hash("f7.json"), hash("s7.json"));
    EXPECT_NE(hash("f7.json"), hash("f0.json"));
    const RunResult bad = run("render scene.json --fiber-seed -1 --out bad.exr");
    EXPECT_EQ(bad.status, 2);
    EXPECT_TRUE(testing::contains(bad.err, "--fiber-seed: a seed is an integer in [0, 2^64 - 1]"))
        << bad.err;
}

TEST_F(RenderCliTest, TimeBudgetAndSceneDefaults) {
    RunResult r = run("render scene.json --time 0.5 --quiet --out timed.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json stats = nlohmann::json::parse(readFile(path("timed.json")));
    EXPECT_GE(stats.at("spp").get<int>(), 1);
    // Without a budget flag the scene's render.spp (2) is used.
    r = run("render scene.json --quiet --out default.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(readFile(path("default.json"))).at("spp"), 2);
}

// The sampling ablation of paper Fig. 5: the same image in expectation, another estimator.
TEST_F(RenderCliTest, CosineYarnSampling) {
    const RunResult r =
        run("render scene.json --spp 2 --yarn-sampling cosine --quiet --out cos.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    const Image image = readImage(path("cos.exr"));
    double sum = 0;
    for (float v : image.pixels) {
        ASSERT_TRUE(std::isfinite(v));
        sum += v;
    }
    EXPECT_GT(sum, 0.0);
    EXPECT_EQ(nlohmann::json::parse(readFile(path("cos.json"))).at("yarn_sampling"), "cosine");
    ASSERT_EQ(run("render scene.json --spp 2 --quiet --out tabulated.exr").status, 0);
    EXPECT_EQ(nlohmann::json::parse(readFile(path("tabulated.json"))).at("yarn_sampling"),
              "tabulated");
    EXPECT_NE(readImage(path("tabulated.exr")).pixels, image.pixels);
    ASSERT_EQ(
        run("render scene.json --spp 2 --yarn-sampling fitted --quiet --out fitted.exr").status, 0);
    EXPECT_EQ(nlohmann::json::parse(readFile(path("fitted.json"))).at("yarn_sampling"), "fitted");
    EXPECT_NE(readImage(path("fitted.exr")).pixels, image.pixels);
    expectUserError(run("render scene.json --spp 1 --yarn-sampling x --out x.exr"),
                    {"--yarn-sampling", "\"x\"", "tabulated, fitted, cosine"});
}

// --sampler sobol: recorded in the statistics, deterministic, another estimator
// of the same image (the sampler tests are in core/sample_stream_test.cpp).
TEST_F(RenderCliTest, SobolSampler) {
    ASSERT_EQ(
        run("render scene.json --spp 4 --sampler sobol --threads 1 --quiet --out s1.exr").status,
        0);
    ASSERT_EQ(
        run("render scene.json --spp 4 --sampler sobol --threads 2 --quiet --out s2.exr").status,
        0);
    ASSERT_EQ(run("render scene.json --spp 4 --quiet --out ind.exr").status, 0);
    EXPECT_EQ(nlohmann::json::parse(readFile(path("s1.json"))).at("sampler"), "sobol");
    EXPECT_EQ(nlohmann::json::parse(readFile(path("ind.json"))).at("sampler"), "independent");
    const Image sobol = readImage(path("s1.exr")), independent = readImage(path("ind.exr"));
    EXPECT_EQ(readImage(path("s2.exr")).pixels, sobol.pixels);
    EXPECT_NE(independent.pixels, sobol.pixels);
    double a = 0, b = 0;
    for (size_t i = 0; i < sobol.pixels.size(); ++i)
        a += sobol.pixels[i], b += independent.pixels[i];
    EXPECT_NEAR(a / b, 1.0, 0.1);
    expectUserError(run("render scene.json --spp 1 --sampler halton --out x.exr"),
                    {"--sampler", "\"halton\"", "independent, sobol"});
}

// --integrator path|batch|auto: the same image bit for bit (render_test holds
// the integrators to that in detail); a bad name is refused with the allowed ones.
TEST_F(RenderCliTest, IntegratorsGiveTheSameImage) {
    for (const char* integrator : {"auto", "path", "batch"})
        ASSERT_EQ(run(std::string("render scene.json --spp 2 --quiet --integrator ") + integrator +
                      " --out " + integrator + ".exr")
                      .status,
                  0)
            << integrator;
    const Image batch = readImage(path("batch.exr"));
    EXPECT_EQ(readImage(path("path.exr")).pixels, batch.pixels);
    EXPECT_EQ(readImage(path("auto.exr")).pixels, batch.pixels);
    expectUserError(run("render scene.json --spp 1 --integrator wavefront --out x.exr"),
                    {"--integrator", "\"wavefront\"", "auto, path, batch"});
}

// `weft render --shard K/N` and `weft render merge`: the merge of the parts is
// the unsharded image up to float rounding, and bad sets of parts are refused
// without writing anything.
TEST_F(RenderCliTest, ShardedRenderMergesToTheUnshardedImage) {
    ASSERT_EQ(run("render scene.json --spp 5 --quiet --out whole.exr").status, 0);
    for (int k = 0; k < 3; ++k) {
        const std::string part = "part" + std::to_string(k);
        const RunResult r = run("render scene.json --spp 5 --shard " + std::to_string(k) +
                                "/3 --threads 1 --quiet --out " + part + ".exr");
        ASSERT_EQ(r.status, 0) << r.err;
        const nlohmann::json shard =
            nlohmann::json::parse(readFile(path(part + ".json"))).at("shard");
        EXPECT_EQ(shard.at("index"), k);
        EXPECT_EQ(shard.at("count"), 3);
        EXPECT_EQ(shard.at("spp"), 5);
    }
    RunResult r = run("render merge part2.exr part0.exr part1.exr --out merged.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    const Image whole = readImage(path("whole.exr")), merged = readImage(path("merged.exr"));
    ASSERT_EQ(merged.pixels.size(), whole.pixels.size());
    for (size_t i = 0; i < whole.pixels.size(); ++i)
        ASSERT_NEAR(merged.pixels[i], whole.pixels[i], 1e-6 * whole.pixels[i] + 1e-12) << i;
    const nlohmann::json stats = nlohmann::json::parse(readFile(path("merged.json")));
    EXPECT_EQ(stats.at("spp"), 5);
    EXPECT_EQ(stats.at("shards").at("count"), 3);
    EXPECT_FALSE(stats.contains("shard"));
    EXPECT_TRUE(std::filesystem::exists(path("merged.png")));

    // A missing part, a part twice, a part of another render, a whole render.
    expectUserError(run("render merge part0.exr part2.exr --out bad.exr"), {"missing", "1/3"});
    expectUserError(run("render merge part0.exr part1.exr part1.exr part2.exr --out bad.exr"),
                    {"both shard 1/3"});
    ASSERT_EQ(run("render scene.json --spp 5 --seed 9 --shard 1/3 --quiet --out other.exr").status,
              0);
    expectUserError(run("render merge part0.exr other.exr part2.exr --out bad.exr"),
                    {"other.json", "\"seed\""});
    expectUserError(run("render merge whole.exr --out bad.exr"), {"whole.json", "not a part"});
    // A damaged last part: the merge fails after reading the others and writes nothing.
    const std::string bytes = readFile(path("part2.exr"));
    writeFileAtomic(path("part2.exr"), bytes.substr(0, bytes.size() / 2));
    expectUserError(run("render merge part0.exr part1.exr part2.exr --out bad.exr"), {"part2.exr"});
    EXPECT_FALSE(std::filesystem::exists(path("bad.exr")));
    EXPECT_FALSE(std::filesystem::exists(path("bad.json")));
    for (const auto& entry : std::filesystem::directory_iterator(dir_))
        EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
    // Bad shards.
    expectUserError(run("render scene.json --spp 2 --shard 2/2 --out a.exr"), {"--shard", "2/2"});
    expectUserError(run("render scene.json --spp 2 --shard 0/3 --out a.exr"),
                    {"--shard", "N <= 2"});
    expectUserError(run("render scene.json --time 1 --shard 0/2 --out a.exr"),
                    {"--shard", "--spp"});
    expectUserError(run("render scene.json --spp 2 --shard x --out a.exr"), {"--shard", "K/N"});
}

// Issue 41: bytes flipped inside a part's ZIP-compressed pixels may still
// decode, to pixels up to 1e33 that the merge averaged in with exit 0. A
// part's JSON carries the FNV-1a checksum of its pixels, which the merge
// verifies; a part without one (an older weft) is refused with the advice to
// render it again.
TEST_F(RenderCliTest, MergeRefusesACorruptedOrUncheckedPart) {
    for (int k = 0; k < 2; ++k)
        ASSERT_EQ(run("render scene.json --spp 4 --shard " + std::to_string(k) +
                      "/2 --quiet --out part" + std::to_string(k) + ".exr")
                      .status,
                  0);
    const nlohmann::json stats = nlohmann::json::parse(readFile(path("part1.json")));
    // The checksum is FNV-1a 64 of the float32 pixels as the EXR holds them,
    // computed here byte by byte from the image read back.
    uint64_t fnv = 0xcbf29ce484222325ULL;
    for (const float v : readImage(path("part1.exr")).pixels) {
        uint32_t bits = 0;
        std::memcpy(&bits, &v, 4);
        for (int byte = 0; byte < 4; ++byte) fnv = (fnv ^ (bits >> (8 * byte) & 0xff)) * 0x100000001b3ULL;
    }
    char expected[32];
    std::snprintf(expected, sizeof expected, "fnv1a64:%016llx", static_cast<unsigned long long>(fnv));
    EXPECT_EQ(stats.at("shard").at("checksum"), expected);
    ASSERT_EQ(run("render merge part0.exr part1.exr --out merged.exr").status, 0);
    const Image merged = readImage(path("merged.exr"));
    const std::string exr = readFile(path("part1.exr")), json = readFile(path("part1.json"));
    // 8 bytes flipped at offsets through the second half of the file (the
    // compressed pixels); each corruption is refused, naming the part.
    int checksumFailures = 0, corruptions = 0;
    for (size_t at = exr.size() / 2; at + 8 < exr.size(); at += exr.size() / 10, ++corruptions) {
        std::string bytes = exr;
        for (size_t i = at; i < at + 8; ++i) bytes[i] = static_cast<char>(~bytes[i]);
        writeFileAtomic(path("part1.exr"), bytes);
        const RunResult r = run("render merge part0.exr part1.exr --out bad.exr");
        expectUserError(r, {"part1.exr"});
        checksumFailures += testing::contains(r.err, "checksum");
    }
    EXPECT_GT(corruptions, 4);
    EXPECT_GT(checksumFailures, 0) << "no corruption decoded: the test does not reach the checksum";
    EXPECT_FALSE(std::filesystem::exists(path("bad.exr")));
    // The same bytes again: the same merge.
    writeFileAtomic(path("part1.exr"), exr);
    ASSERT_EQ(run("render merge part0.exr part1.exr --out again.exr").status, 0);
    EXPECT_EQ(readImage(path("again.exr")).pixels, merged.pixels);
    // A checksum missing (a part of an older weft), malformed, or of other pixels.
    nlohmann::json edited = stats;
    edited["shard"].erase("checksum");
    writeFileAtomic(path("part1.json"), edited.dump(2));
    expectUserError(run("render merge part0.exr part1.exr --out bad.exr"),
                    {"part1.json", "shard.checksum", "render this part again"});
    edited["shard"]["checksum"] = "sha1:0123";
    writeFileAtomic(path("part1.json"), edited.dump(2));
    expectUserError(run("render merge part0.exr part1.exr --out bad.exr"),
                    {"part1.json", "shard.checksum", "fnv1a64:"});
    edited["shard"]["checksum"] =
        nlohmann::json::parse(readFile(path("part0.json"))).at("shard").at("checksum");
    writeFileAtomic(path("part1.json"), edited.dump(2));
    expectUserError(run("render merge part0.exr part1.exr --out bad.exr"),
                    {"part1.exr", "checksum", "part1.json"});
    EXPECT_FALSE(std::filesystem::exists(path("bad.exr")));
    writeFileAtomic(path("part1.json"), json);
    EXPECT_EQ(run("render merge part0.exr part1.exr --out again.exr").status, 0);
    // Parts whose JSON claim a 65536 x 65536 film: the merge allocates its
    // sums once the first image has been read and matched (before: 103 GB
    // from the claim alone, "out of memory").
    for (const char* part : {"part0.json", "part1.json"}) {
        nlohmann::json claim = nlohmann::json::parse(readFile(path(part)));
        claim["width"] = claim["height"] = 65536;
        writeFileAtomic(path(part), claim.dump(2));
    }
    expectUserError(run("render merge part0.exr part1.exr --out bad.exr"),
                    {"part0.exr", "16 x 12 pixels", "65536 x 65536"});
}

// Two parallel yarns 0.03 apart drawn with radius 0.03: the whole length of
// each lies inside the other, by (0.06 - 0.03) / 0.06 = half the diameter.
TEST_F(RenderCliTest, WarnsWhenYarnsOverlap) {
    writeFileAtomic(path("pair.txt"), "-0.2 0 0\n0.2 0 0\n\n-0.2 0.03 0\n0.2 0.03 0\n");
    writeFileAtomic(path("pair.json"), R"({
        "camera": {"from": [0, 0, 1], "to": [0, 0, 0], "fov_deg": 8},
        "film": {"width": 16, "height": 12},
        "render": {"spp": 1, "seed": 1},
        "yarns": [{"curves": "pair.txt", "radius": 0.03, "model": ")" +
                                           kFleece + R"("}]
    })");
    for (const std::string mode : {"neural", "fiber"}) {
        const RunResult r = run("render pair.json --mode " + mode + " --out " + mode + ".exr");
        ASSERT_EQ(r.status, 0) << r.err;
        EXPECT_TRUE(testing::contains(
            r.err, "weft: warning: pair.json: yarns[0] (" + path("pair.txt") +
                       "): 100.0% of the yarn length lies inside other yarns (up to 50% of the "
                       "diameter) at radius 0.03; the largest radius without overlap is 0.015\n"))
            << r.err;
        const nlohmann::json overlap =
            nlohmann::json::parse(readFile(path(mode + ".json"))).at("yarn_overlap");
        ASSERT_EQ(overlap.size(), 1u);
        EXPECT_EQ(overlap[0].at("yarn"), 0);
        EXPECT_EQ(overlap[0].at("curves"), path("pair.txt"));
        EXPECT_EQ(overlap[0].at("radius"), 0.03);
        EXPECT_EQ(overlap[0].at("overlap_fraction"), 1.0);
        EXPECT_NEAR(overlap[0].at("max_overlap").get<double>(), 0.5, 1e-6);
        EXPECT_NEAR(overlap[0].at("largest_radius_without_overlap").get<double>(), 0.015, 1e-8);
    }
    // --quiet: no warning (and no progress), the statistics keep the record.
    RunResult r = run("render pair.json --quiet --out quiet.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(r.err, "");
    EXPECT_EQ(nlohmann::json::parse(readFile(path("quiet.json"))).at("yarn_overlap"),
              nlohmann::json::parse(readFile(path("neural.json"))).at("yarn_overlap"));
    // One yarn alone: recorded, not warned about; no contact, no largest radius.
    r = run("render scene.json --out alone.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_FALSE(testing::contains(r.err, "warning")) << r.err;
    const nlohmann::json alone =
        nlohmann::json::parse(readFile(path("alone.json"))).at("yarn_overlap");
    ASSERT_EQ(alone.size(), 1u);
    EXPECT_EQ(alone[0].at("overlap_fraction"), 0.0);
    EXPECT_TRUE(alone[0].at("largest_radius_without_overlap").is_null());
}

// A shallow render.max_depth cuts fiber paths: counted in the statistics,
// warned about (also with --quiet: the image is biased), summed by a merge.
TEST_F(RenderCliTest, WarnsWhenPathsAreCutAtMaxDepth) {
    std::string text = readFile(path("scene.json"));
    text.replace(text.find("\"spp\": 2,"), 9, "\"spp\": 4, \"max_depth\": 2,");
    writeFileAtomic(path("shallow-scene.json"), text);
    RunResult r = run("render shallow-scene.json --mode fiber --quiet --out shallow.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_TRUE(testing::contains(r.err, "weft: warning: "));
    EXPECT_TRUE(testing::contains(r.err, "reached render.max_depth = 2 scattering events"))
        << r.err;
    const nlohmann::json stats = nlohmann::json::parse(readFile(path("shallow.json")));
    const int64_t cut = stats.at("truncated_paths").get<int64_t>();
    EXPECT_GT(cut, 0);
    EXPECT_NEAR(stats.at("truncated_fraction").get<double>(), cut / (16.0 * 12.0 * 4.0), 1e-12);
    // Shards trace the same paths: their merge counts the same cut paths.
    for (int k = 0; k < 2; ++k)
        ASSERT_EQ(run("render shallow-scene.json --mode fiber --quiet --shard " +
                      std::to_string(k) + "/2 --out s" + std::to_string(k) + ".exr")
                      .status,
                  0);
    ASSERT_EQ(run("render merge s0.exr s1.exr --out merged.exr").status, 0);
    const nlohmann::json merged = nlohmann::json::parse(readFile(path("merged.json")));
    EXPECT_EQ(merged.at("truncated_paths"), cut);
    EXPECT_EQ(merged.at("truncated_fraction"), stats.at("truncated_fraction"));
    // The default depth cuts nothing here: no warning.
    r = run("render scene.json --mode fiber --quiet --out deep.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(r.err, "");
    EXPECT_EQ(nlohmann::json::parse(readFile(path("deep.json"))).at("truncated_paths"), 0);
}

TEST_F(RenderCliTest, YarnColourInEveryMode) {
    // fleece-small's C_TT is (0.452, 0.725, 0.948); a green yarn instead.
    writeScene("green.json", R"(, "colour": [0.2, 0.9, 0.2])");
    for (const std::string mode : {"fiber", "dual"}) {
        ASSERT_EQ(
            run("render scene.json --mode " + mode + " --spp 4 --quiet --out " + mode + ".exr")
                .status,
            0);
        const RunResult r = run("render green.json --mode " + mode + " --spp 4 --quiet --out " +
                                mode + "-green.exr");
        ASSERT_EQ(r.status, 0) << r.err;
        const Rgb plain = eval::channelMeans(readImage(path(mode + ".exr")));
        const Rgb green = eval::channelMeans(readImage(path(mode + "-green.exr")));
        EXPECT_LT(green.r, plain.r) << mode;
        EXPECT_GT(green.g, plain.g) << mode;
        EXPECT_LT(green.b, plain.b) << mode;
    }
    // Neural mode needs a colour-conditioned model.
    expectUserError(run("render green.json --spp 2 --quiet --out x.exr"),
                    {"green.json: yarns[0].colour", "fitted for one colour", "--colour-range"});
    writeScene("bad.json", R"(, "colour": [1.5, 0, 0])");
    expectUserError(run("render bad.json --mode fiber --spp 2 --quiet --out x.exr"),
                    {"bad.json", "colour", "[0, 1]"});

    // A conditioned model: without a colour it renders its gathered colour,
    // which "colour" then reproduces exactly.
    writeFileAtomic(path("short.json"), R"({"t_net": {"steps": 100, "batch": 64},
        "m_net": {"hidden": [8, 8], "steps": 100, "batch": 64}, "appearance_nodes": 5})");
    ASSERT_EQ(run("gather --preset fleece --paths 3000 --bins 4,8,6,12 --any-colour --quiet "
                  "--out ac")
                  .status,
              0);
    ASSERT_EQ(run("fit --rdm ac --out any.json --config short.json --colour-range 0.3,0.999 "
                  "--colour-functions 3 --no-report --quiet")
                  .status,
              0);
    const auto sceneWith = [&](const std::string& name, const std::string& colour) {
        std::string text = readFile(path("scene.json"));
        text.replace(text.find(kFleece), kFleece.size(), path("any.json"));
        if (!colour.empty())
            text.replace(text.find("\"model\""), 0, "\"colour\": " + colour + ", ");
        writeFileAtomic(path(name), text);
    };
    sceneWith("any.scene.json", "");
    sceneWith("own.scene.json", "[0.452, 0.725, 0.948]");
    sceneWith("red.scene.json", "[0.9, 0.35, 0.3]");
    // Below the model's colour range [0.3, 0.999]: refused, never clamped.
    sceneWith("dark.scene.json", "[0.9, 0.1, 0.1]");
    expectUserError(run("render dark.scene.json --spp 1 --quiet --out x.exr"),
                    {"dark.scene.json: yarns[0].colour", "C_TT 0.1", "colour range [0.3, 0.999]",
                     "appearance"});
    for (const char* name : {"any", "own", "red"}) {
        const RunResult r = run(std::string("render ") + name +
                                ".scene.json --spp 2 --quiet --out img-" + name + ".exr");
        ASSERT_EQ(r.status, 0) << name << ": " << r.err;
    }
    EXPECT_EQ(readImage(path("img-own.exr")).pixels, readImage(path("img-any.exr")).pixels);
    EXPECT_NE(readImage(path("img-red.exr")).pixels, readImage(path("img-any.exr")).pixels);
    // Vertex colours of one colour are that colour, in neural mode too.
    writeFileAtomic(path("red3.txt"), "0.9 0.35 0.3\n0.9 0.35 0.3\n0.9 0.35 0.3\n");
    std::string text = readFile(path("red.scene.json"));
    const std::string colourKey = "\"colour\": [0.9, 0.35, 0.3]";
    text.replace(text.find(colourKey), colourKey.size(), "\"vertex_colours\": \"red3.txt\"");
    writeFileAtomic(path("red3.scene.json"), text);
    const RunResult r = run("render red3.scene.json --spp 2 --quiet --out img-red3.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(readImage(path("img-red3.exr")).pixels, readImage(path("img-red.exr")).pixels);
}

// Colour by appearance (docs/colour.md): the scene's sRGB colour becomes the
// C_TT that `weft yarn appearance` finds, whose appearance evaluated directly
// (by quadrature, not the table) is the colour asked; every mode draws it.
TEST_F(RenderCliTest, AppearanceBecomesTheFiberColourThatLooksIt) {
    const std::string model = std::string(WEFT_SOURCE_DIR) + "/tests/data/fleece-colour-small.json";
    const RunResult probe = run("yarn appearance --model " + model + " --appearance '#a0704a'");
    ASSERT_EQ(probe.status, 0) << probe.err;
    const nlohmann::json p = nlohmann::json::parse(probe.out);
    const double bytes[3] = {0xa0, 0x70, 0x4a};
    for (int c = 0; c < 3; ++c) {
        const double want = p["appearance"]["linear"][c].get<double>();
        EXPECT_NEAR(p["appearance_direct"][c].get<double>(), want, 0.005 * want) << c;
        EXPECT_NEAR(p["appearance"]["srgb"][c].get<double>(), bytes[c] / 255.0, 1e-12);
    }
    std::string text = readFile(path("scene.json"));
    text.replace(text.find(kFleece), kFleece.size(), model);
    const auto withKey = [&](const std::string& name, const std::string& key) {
        std::string t = text;
        t.replace(t.find("\"model\""), 0, key + ", ");
        writeFileAtomic(path(name), t);
    };
    withKey("look.json", R"("appearance": "#a0704a")");
    for (const std::string mode : {"neural", "fiber"}) {
        const RunResult r =
            run("render look.json --mode " + mode + " --spp 1 --out " + mode + ".exr");
        ASSERT_EQ(r.status, 0) << r.err;
        EXPECT_NE(r.err.find("look.json: yarns[0]: appearance (sRGB 0.627"), std::string::npos)
            << r.err;
        const nlohmann::json stats = nlohmann::json::parse(readFile(path(mode + ".json")));
        ASSERT_EQ(stats["appearance"].size(), 1u);
        EXPECT_EQ(stats["appearance"][0]["c_tt"], p["c_tt"]) << mode;
    }
    withKey("white.json", R"("appearance": [1, 1, 1])");
    expectUserError(run("render white.json --spp 1 --quiet --out x.exr"),
                    {"white.json: yarns[0].appearance", "red 1", "out of reach", "sRGB"});
    withKey("both.json", R"("appearance": "#a0704a", "colour": [0.5, 0.5, 0.5])");
    expectUserError(run("render both.json --spp 1 --quiet --out x.exr"),
                    {"both.json", "appearance", "not both"});
    withKey("hex.json", R"("appearance": "#a0704")");
    expectUserError(run("render hex.json --spp 1 --quiet --out x.exr"), {"hex.json", "#rrggbb"});
    writeScene("plain.json", R"(, "appearance": [0.5, 0.4, 0.3])");
    expectUserError(run("render plain.json --mode fiber --spp 1 --quiet --out x.exr"),
                    {"plain.json: yarns[0].appearance", "fitted for one colour"});
}

// The mean colour of the pixels in columns [x0, x1) of the middle two rows.
Rgb meanColourOfColumns(const Image& image, int x0, int x1) {
    Rgb sum;
    for (int y = image.height / 2 - 1; y <= image.height / 2; ++y)
        for (int x = x0; x < x1; ++x)
            for (int c = 0; c < 3; ++c)
                sum[c] += image.pixels[3 * (static_cast<size_t>(y) * image.width + x) + c];
    return sum / static_cast<double>(2 * (x1 - x0));
}

TEST_F(RenderCliTest, VertexColoursInEveryMode) {
    // One colour at every point: the same image as "colour", bit for bit.
    writeFileAtomic(path("green3.txt"), "0.2 0.9 0.2\n0.2 0.9 0.2\n0.2 0.9 0.2\n");
    writeScene("green.json", R"(, "colour": [0.2, 0.9, 0.2])");
    writeScene("green3.json", R"(, "vertex_colours": "green3.txt")");
    for (const std::string mode : {"fiber", "dual"}) {
        for (const char* name : {"green", "green3"}) {
            const RunResult r = run(std::string("render ") + name + ".json --mode " + mode +
                                    " --spp 2 --quiet --out " + mode + "-" + name + ".exr");
            ASSERT_EQ(r.status, 0) << r.err;
        }
        EXPECT_EQ(readImage(path(mode + "-green3.exr")).pixels,
                  readImage(path(mode + "-green.exr")).pixels)
            << mode;
    }
    // Space-dyed: red left of x = 0, blue right of it (a wide view of a
    // straight yarn). Two materials, and each half of the image its colour.
    writeFileAtomic(path("long.txt"), "-0.5 0 0\n-0.0005 0 0\n0.0005 0 0\n0.5 0 0\n");
    writeFileAtomic(path("dyed.txt"), "0.9 0.1 0.1\n0.9 0.1 0.1\n0.1 0.1 0.9\n0.1 0.1 0.9\n");
    std::string text = readFile(path("green3.json"));
    text.replace(text.find("yarn.txt"), 8, "long.txt");
    text.replace(text.find("green3.txt"), 10, "dyed.txt");
    text.replace(text.find("\"fov_deg\": 8"), 12, "\"fov_deg\": 30");
    writeFileAtomic(path("dyed.json"), text);
    for (const std::string mode : {"fiber", "dual"}) {
        const RunResult r =
            run("render dyed.json --mode " + mode + " --spp 8 --quiet --out dyed-" + mode + ".exr");
        ASSERT_EQ(r.status, 0) << r.err;
        const nlohmann::json stats =
            nlohmann::json::parse(readFile(path("dyed-" + mode + ".json")));
        EXPECT_EQ(stats.at("scene").at("materials"), 2) << mode;
        const Image image = readImage(path("dyed-" + mode + ".exr"));
        const Rgb left = meanColourOfColumns(image, 0, image.width / 2 - 1);
        const Rgb right = meanColourOfColumns(image, image.width / 2 + 1, image.width);
        EXPECT_GT(left.r / left.b, 1.2 * right.r / right.b) << mode << ": " << left << " " << right;
    }
    // Neural mode needs a colour-conditioned model; a bad file is named by line.
    expectUserError(run("render dyed.json --spp 2 --quiet --out x.exr"),
                    {"dyed.json: yarns[0].vertex_colours", "fitted for one colour"});
    writeFileAtomic(path("dyed.txt"), "0.9 0.1 0.1\n0.9 0.1\n");
    expectUserError(run("render dyed.json --mode fiber --spp 2 --quiet --out x.exr"),
                    {"dyed.txt:2:", "'r g b'"});
    writeFileAtomic(path("dyed.txt"), "0.9 0.1 0.1\n0.9 0.1 0.1\n0.1 0.1 0.9\n");
    expectUserError(run("render dyed.json --mode fiber --spp 2 --quiet --out x.exr"),
                    {"dyed.txt", "curve 0 has 3 colours but 4 points"});
    // Every point its own colour: more materials than a scene may have.
    std::string many, manyColours;
    for (int k = 0; k < 300; ++k) {
        many += std::to_string(-0.5 + k / 299.0) + " 0 0\n";
        manyColours += std::to_string(k / 299.0) + " 0.5 0.5\n";
    }
    writeFileAtomic(path("long.txt"), many);
    writeFileAtomic(path("dyed.txt"), manyColours);
    expectUserError(run("render dyed.json --mode fiber --spp 1 --quiet --out x.exr"),
                    {"dyed.json: yarns[0]", "more than 256 materials"});
    EXPECT_FALSE(std::filesystem::exists(path("x.exr")));
}

TEST_F(RenderCliTest, BadInputIsNamed) {
    expectUserError(run("render scene.json --spp 2 --time 1 --out a.exr"), {"--spp", "--time"});
    expectUserError(run("render scene.json --spp 0 --out a.exr"), {"--spp"});
    expectUserError(run("render scene.json --spp 1 --mode fibre --out a.exr"), {"fibre", "neural"});
    expectUserError(run("render scene.json --spp 1 --out a.png"), {"a.png", ".exr"});
    expectUserError(run("render missing.json --spp 1 --out a.exr"), {"missing.json"});
    expectUserError(run("render scene.json --spp 1 --threads -2 --out a.exr"), {"--threads"});
    writeScene("bad.json", R"(, "plys": 3)");
    expectUserError(run("render bad.json --spp 1 --out a.exr"), {"bad.json", "plys"});
    expectUserError(run("render scene.json --spp 1 --checkpoint 0.05 --out a.exr"),
                    {"--checkpoint", "[0.1, 1e6]"});
    writeFileAtomic(path("yarn.txt"), "0 0 0\n1 nan 0\n");
    expectUserError(run("render scene.json --spp 1 --out a.exr"), {"yarn.txt", "2"});
    EXPECT_FALSE(std::filesystem::exists(path("a.exr")));
}

// Issue 43, item 5: an animation. Curves named with a frame pattern render
// to numbered outputs; a frame whose files are the same renders the same
// image (one seed for every frame: static parts do not flicker); frames
// finished earlier are kept, a changed or partial one is rendered again;
// --frame-shard K/N takes every N-th frame; a turntable turns the camera.
TEST_F(RenderCliTest, AnimationFramesResumeShardAndTurntable) {
    const std::string still = "-0.2 0 0\n0 0.01 0\n0.2 0 0\n";
    writeFileAtomic(path("yarn.0001.txt"), still);
    writeFileAtomic(path("yarn.0002.txt"), still);
    writeFileAtomic(path("yarn.0003.txt"), "-0.2 0.02 0\n0 0.03 0\n0.2 0.02 0\n");
    nlohmann::json scene = nlohmann::json::parse(readFile(path("scene.json")));
    scene["yarns"][0]["curves"] = "yarn.%04d.txt";
    writeFileAtomic(path("anim.json"), scene.dump());
    expectUserError(run("render anim.json --out a.exr"), {"anim.json", "--frames"});
    RunResult r = run("render anim.json --frames 1:3 --quiet --out a.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    const auto pixels = [&](const std::string& f) { return readImage(path(f)).pixels; };
    EXPECT_EQ(pixels("a.0001.exr"), pixels("a.0002.exr"));
    EXPECT_NE(pixels("a.0001.exr"), pixels("a.0003.exr"));
    EXPECT_EQ(nlohmann::json::parse(readFile(path("a.0003.json"))).at("frame"), 3);
    // Resume: 1 kept; 2 was partial, 3's curves changed: both rendered again.
    nlohmann::json stats = nlohmann::json::parse(readFile(path("a.0002.json")));
    stats["partial"] = true;
    writeFileAtomic(path("a.0002.json"), stats.dump());
    writeFileAtomic(path("yarn.0003.txt"), "-0.2 0.03 0\n0 0.03 0\n0.2 0.03 0\n");
    r = run("render anim.json --frames 1:3 --quiet --out a.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_TRUE(contains(r.out, R"({"exr":"a.0001.exr","frame":1,"kept":true})")) << r.out;
    EXPECT_FALSE(contains(r.out, R"("frame":2,"kept")")) << r.out;
    EXPECT_FALSE(contains(r.out, R"("frame":3,"kept")")) << r.out;
    EXPECT_FALSE(nlohmann::json::parse(readFile(path("a.0002.json"))).at("partial").get<bool>());
    // A shard of the frames, and --out's own pattern.
    r = run("render anim.json --frames 1:3 --frame-shard 1/2 --quiet --out s-%02d.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_FALSE(std::filesystem::exists(path("s-01.exr")));
    EXPECT_TRUE(std::filesystem::exists(path("s-02.exr")));
    EXPECT_FALSE(std::filesystem::exists(path("s-03.exr")));
    // A turntable of a still yarn: frame 1 is the camera as given, frame 3 of 4 looks from behind.
    r = run("render scene.json --frames 1:4 --turntable 360 --quiet --out t.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    ASSERT_EQ(run("render scene.json --quiet --out plain.exr").status, 0);
    EXPECT_EQ(pixels("t.0001.exr"), pixels("plain.exr"));
    EXPECT_NE(pixels("t.0002.exr"), pixels("plain.exr"));
    // Bad patterns and flags are named.
    scene["yarns"][0]["curves"] = "yarn.%x.txt";
    writeFileAtomic(path("bad.json"), scene.dump());
    expectUserError(run("render bad.json --frames 1:2 --out b.exr"), {"yarns[0].curves", "%0Nd"});
    expectUserError(run("render anim.json --frames 3:1 --out b.exr"), {"--frames", "FIRST:LAST"});
    expectUserError(run("render anim.json --frames 1:2 --shard 0/2 --out b.exr"),
                    {"--frame-shard"});
    expectUserError(run("render scene.json --frame-shard 0/2 --out b.exr"),
                    {"--frame-shard", "--frames"});
}

// Issue 43, item 4: --aov writes IMAGE.<pass>.exr beside the image (listed in
// the statistics' outputs); --exposure auto picks and records the stops.
TEST_F(RenderCliTest, PassesAndAutoExposure) {
    RunResult r =
        run("render scene.json --spp 2 --aov albedo,depth,yarn_id,normal --exposure auto "
            "--quiet --out p.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    for (const std::string pass : {"albedo", "normal", "depth", "yarn_id"}) {
        const Image image = readImage(path("p." + pass + ".exr"));
        EXPECT_EQ(image.width, 16);
        EXPECT_EQ(image.height, 12);
    }
    const nlohmann::json stats = nlohmann::json::parse(readFile(path("p.json")));
    EXPECT_EQ(stats.at("outputs").at("depth"), "p.depth.exr");
    EXPECT_TRUE(stats.at("exposure_auto").get<bool>());
    EXPECT_NEAR(stats.at("exposure").get<double>(), autoExposure(readImage(path("p.exr"))), 1e-9);
    expectUserError(run("render scene.json --spp 1 --aov albedo,zdepth --out q.exr"),
                    {"--aov", "zdepth", "albedo, normal, depth, yarn_id"});
    expectUserError(run("render scene.json --spp 2 --shard 0/2 --aov depth --out q.exr"),
                    {"--aov", "--shard"});
    expectUserError(run("render scene.json --spp 1 --exposure bright --out q.exr"),
                    {"--exposure", "bright", "auto"});
    expectUserError(run("render scene.json --spp 1 --exposure 65 --out q.exr"),
                    {"--exposure", "[-64, 64]"});
    EXPECT_FALSE(std::filesystem::exists(path("q.exr")));
}

// Issue 43, item 3: outputs that cannot be written fail before the render
// (a million spp would not finish within the test's time), naming the flag.
TEST_F(RenderCliTest, OutputsAreCheckedBeforeTheRender) {
    RunResult r = run("render scene.json --spp 1000000 --out missing/a.exr");
    expectUserError(r, {"--out", "missing/a.exr"});
    std::filesystem::create_directory(path("a.png"));
    r = run("render scene.json --spp 1000000 --out a.exr");
    expectUserError(r, {"--out's PNG", "a.png", "directory"});
    EXPECT_FALSE(std::filesystem::exists(path("a.exr")));
}

// `weft render knit.json --out knit.exr`: the statistics go to knit.render.json,
// never over the scene, and `weft render merge` finds them there.
TEST_F(RenderCliTest, StatisticsNeverReplaceTheScene) {
    const std::string scene = readFile(path("scene.json"));
    RunResult r = run("render scene.json --spp 2 --quiet --out scene.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(readFile(path("scene.json")), scene);
    EXPECT_EQ(nlohmann::json::parse(r.out).at("json"), "scene.render.json");
    EXPECT_EQ(nlohmann::json::parse(readFile(path("scene.render.json"))).at("spp"), 2);
    ASSERT_EQ(run("render scene.json --spp 2 --shard 0/2 --quiet --out scene.exr").status, 0);
    ASSERT_EQ(run("render scene.json --spp 2 --shard 1/2 --quiet --out part1.exr").status, 0);
    r = run("render merge scene.exr part1.exr --out merged.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(readFile(path("merged.json"))).at("spp"), 2);
    EXPECT_EQ(readFile(path("scene.json")), scene);
}

// Issue 43, item 3: --checkpoint writes the image while rendering; the first
// SIGINT or SIGTERM finishes the tiles in flight, writes the image so far
// ("partial": true) and exits 130 or 143; `weft compare` reads that image.
TEST_F(RenderCliTest, SignalsAndCheckpointsKeepTheWork) {
    ASSERT_EQ(run("render scene.json --spp 4 --quiet --out ref.exr").status, 0);
    for (const auto& [signal, status] : {std::pair{SIGINT, 130}, std::pair{SIGTERM, 143}}) {
        std::filesystem::remove(path("long.json"));
        const int out = ::open(path("long.out").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        const int err = ::open(path("long.err").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        ASSERT_GE(out, 0);
        ASSERT_GE(err, 0);
        const pid_t child = testing::spawnWeft(
            dir_, "render scene.json --time 100000 --checkpoint 1 --threads 2 --out long.exr", 0,
            out, err);
        ::close(out);
        ::close(err);
        // The first checkpoint: the render is under way (and the image so far on disk).
        bool written = false;
        for (int k = 0; k < 6000 && !written; ++k) {
            written = std::filesystem::exists(path("long.json"));
            if (!written) std::this_thread::sleep_for(std::chrono::milliseconds(50));
        }
        if (!written) ::kill(child, SIGKILL);
        int wstatus = 0;
        if (written) ::kill(child, signal);
        ::waitpid(child, &wstatus, 0);
        ASSERT_TRUE(written) << readFile(path("long.err"));
        EXPECT_EQ(testing::statusOf(wstatus), status) << readFile(path("long.err"));
        const nlohmann::json stats = nlohmann::json::parse(readFile(path("long.json")));
        EXPECT_TRUE(stats.at("partial").get<bool>());
        EXPECT_GE(stats.at("spp").get<int>(), 1);
        EXPECT_GE(stats.at("spp_max").get<int>(), stats.at("spp").get<int>());
        EXPECT_TRUE(contains(readFile(path("long.err")), "stopped by"))
            << readFile(path("long.err"));
        EXPECT_TRUE(nlohmann::json::parse(readFile(path("long.out"))).at("partial").get<bool>());
        const RunResult compared = run("compare long.exr ref.exr");
        EXPECT_EQ(compared.status, 0) << compared.err;
    }
}

// A family model (docs/family.md): each yarn gives its own parameters and
// renders exactly as the model `weft yarn at` writes for them; a yarn
// outside the box, a family model without "yarn" and "yarn" with a model of
// one yarn are refused, naming the entry and the field.
TEST_F(RenderCliTest, FamilyYarnsRenderWithTheirOwnParameters) {
    const std::string family = std::string(WEFT_SOURCE_DIR) + "/models/family.json";
    const std::string tight =
        R"({"fibers": 250, "density": 0.38, "twist": 0.28, "beta_r_deg": 2, "beta_tt_deg": 12,
            "gamma_tt_deg": 21, "c_r": [0.2, 0.3, 0.4]})";
    const auto scene = [&](const std::string& name, const std::string& model,
                           const std::string& yarnKey) {
        writeFileAtomic(path(name), R"({
            "camera": {"from": [0, 0, 1], "to": [0, 0, 0], "fov_deg": 8},
            "film": {"width": 16, "height": 12},
            "render": {"spp": 2, "seed": 1},
            "yarns": [{"curves": "yarn.txt", "radius": 0.03, "plies": 3, "ply_twist": 0.3,
                       "colour": [0.8, 0.5, 0.3], "model": ")" +
                                        model + "\"" + yarnKey + R"(}]
        })");
    };
    scene("fam.json", family, ", \"yarn\": " + tight);
    RunResult r = run("render fam.json --spp 2 --threads 2 --quiet --out family.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    r = run("yarn at --family " + family + " --yarn '" + tight + "' --out tight.json");
    ASSERT_EQ(r.status, 0) << r.err;
    scene("one-yarn.json", path("tight.json"), "");
    r = run("render one-yarn.json --spp 2 --threads 2 --quiet --out at.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    const Image a = readImage(path("family.exr")), b = readImage(path("at.exr"));
    EXPECT_EQ(a.pixels, b.pixels);
    double sum = 0;
    for (float v : a.pixels) sum += v;
    EXPECT_GT(sum, 0.0);

    scene("outside.json", family, R"(, "yarn": {"fibers": 300, "density": 0.3, "twist": 0.5,
          "beta_r_deg": 2, "beta_tt_deg": 12, "gamma_tt_deg": 21, "c_r": [0.2, 0.3, 0.4]})");
    expectUserError(run("render outside.json --spp 1 --out o.exr"),
                    {"outside.json: yarns[0].yarn", "twist", "0.5", "[0, 0.3]"});
    scene("none.json", family, "");
    expectUserError(run("render none.json --spp 1 --out o.exr"),
                    {"none.json: yarns[0]", "family model", "\"yarn\""});
    scene("one.json", kFleece, ", \"yarn\": " + tight);
    expectUserError(run("render one.json --spp 1 --out o.exr"),
                    {"one.json: yarns[0].yarn", "model of one yarn"});
    EXPECT_FALSE(std::filesystem::exists(path("o.exr")));
}

}  // namespace
}  // namespace weft
