// End-to-end tests of `weft gather`: each test runs the built binary (WEFT_BIN)
// in a fresh temporary directory and checks its exit status, its messages and
// the arrays, ply and metadata it writes.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "cli_test_util.h"
#include "weft/core/curves.h"
#include "weft/core/file.h"
#include "weft/core/npy.h"
#include "weft/core/test_util.h"
#include "weft/gather/gather.h"

namespace weft {
namespace {

namespace fs = std::filesystem;

constexpr double kPi = std::numbers::pi;

// Small runs: 3,8,6,12 bins keep every array tiny and every run well under a second.
const std::string kSmall = "--paths 3000 --bins 3,8,6,12 --quiet";
const char* const kNpyFiles[] = {"count.npy", "count_t.npy",   "p_t.npy",  "rdm_r.npy",
                                 "rdm_m.npy", "truncated.npy", "depth.npy"};
// N = 300 fibers cannot be packed at density 0.95 (fiber.json: kLosslessFiber).
const std::string kImpossiblePly =
    "--params fiber.json --fibers 300 --density 0.95 --twist 0 " + kSmall;
// A lossless fiber: c_tt = 1, the Fresnel term splits energy between R and TT.
const std::string kLosslessFiber =
    R"({"c_r":0.04,"c_tt":1,"beta_r_deg":7,"beta_tt_deg":12,"gamma_tt_deg":25})";

using testing::contains;
using testing::RunResult;

// The elements of an array whose descr matches T (checked by the caller).
template <typename T>
std::vector<T> values(const NpyArray& a) {
    std::vector<T> v(a.size());
    EXPECT_EQ(a.bytes.size(), v.size() * sizeof(T));
    if (a.bytes.size() == v.size() * sizeof(T) && !v.empty())
        std::memcpy(v.data(), a.bytes.data(), a.bytes.size());
    return v;
}

// Reads DIR/NAME and checks its dtype and shape.
NpyArray readChecked(const std::string& dir, const std::string& name, const std::string& descr,
                     const std::vector<size_t>& shape) {
    const NpyArray a = readNpy(dir + "/" + name);
    EXPECT_EQ(a.descr, descr) << name;
    EXPECT_EQ(a.shape, shape) << name << ": " << npyShapeString(a.shape);
    return a;
}

class GatherCliTest : public testing::CliTestBase {
  protected:
    RunResult gather(const std::string& args) const { return run("gather " + args); }

    // Runs a gather that must succeed and returns its stdout.
    std::string gatherOk(const std::string& args) const {
        const RunResult r = gather(args);
        EXPECT_EQ(r.status, 0) << "weft gather " << args << "\nstderr: " << r.err;
        return r.out;
    }

    void writeText(const std::string& name, const std::string& text) const {
        writeFileAtomic(path(name), text);
    }

    nlohmann::json meta(const std::string& out) const {
        return nlohmann::json::parse(readFile(path(out) + "/meta.json"));
    }
};

using testing::expectUserError;

// ---------------------------------------------------------------------------
// Successful runs

TEST_F(GatherCliTest, WritesArraysOfTheDocumentedTypesAndShapes) {
    const std::string out = gatherOk("--preset fleece " + kSmall + " --out out");
    const std::string dir = path("out");
    const size_t ti = 3, pi = 8, to = 6, po = 12;

    const auto count = values<int64_t>(readChecked(dir, "count.npy", "<i8", {ti, pi}));
    const auto countT = values<int64_t>(readChecked(dir, "count_t.npy", "<i8", {ti, pi}));
    const auto pT = values<double>(readChecked(dir, "p_t.npy", "<f8", {ti, pi}));
    const auto rdmR = values<float>(readChecked(dir, "rdm_r.npy", "<f4", {ti, pi, to, po, 3}));
    const auto rdmM = values<float>(readChecked(dir, "rdm_m.npy", "<f4", {ti, pi, to, po, 3}));
    const auto rdmMExit =
        values<float>(readChecked(dir, "rdm_m_exit.npy", "<f4", {ti, pi, to, po, 3}));
    const auto trunc = values<double>(readChecked(dir, "truncated.npy", "<f8", {ti, pi, 3}));
    const auto depth = values<int64_t>(readChecked(dir, "depth.npy", "<i8", {1002}));
    const auto offsets =
        values<double>(readChecked(dir, "exit_offset.npy", "<f8", {4, 8, 8193, 3}));
    for (double v : offsets) EXPECT_TRUE(std::isfinite(v) && v >= 0) << v;

    int64_t paths = 0, depthPaths = 0;
    for (int64_t c : count) paths += c;
    for (int64_t d : depth) {
        EXPECT_GE(d, 0);
        depthPaths += d;
    }
    EXPECT_EQ(paths, 3000);
    EXPECT_EQ(depthPaths, 3000);
    // Paths with no interaction (depth 0) are exactly the T paths.
    int64_t tPaths = 0;
    for (int64_t c : countT) tPaths += c;
    EXPECT_EQ(depth[0], tPaths);
    ASSERT_EQ(pT.size(), count.size());
    for (size_t i = 0; i < count.size(); ++i) {
        EXPECT_GE(countT[i], 0);
        EXPECT_LE(countT[i], count[i]) << i;
        const double expected =
            count[i] > 0 ? static_cast<double>(countT[i]) / static_cast<double>(count[i]) : 0.0;
        EXPECT_EQ(pT[i], expected) << "incident bin " << i;
    }
    for (float v : rdmR) EXPECT_TRUE(std::isfinite(v) && v >= 0) << v;
    for (float v : rdmM) EXPECT_TRUE(std::isfinite(v) && v >= 0) << v;
    for (float v : rdmMExit) EXPECT_TRUE(std::isfinite(v) && v >= 0) << v;
    for (double v : trunc) EXPECT_TRUE(std::isfinite(v) && v >= 0) << v;
    // Fleece scatters: some R and some M energy is recorded.
    EXPECT_GT(*std::max_element(rdmR.begin(), rdmR.end()), 0.0f);
    EXPECT_GT(*std::max_element(rdmM.begin(), rdmM.end()), 0.0f);

    // The one-line JSON summary on stdout.
    ASSERT_FALSE(out.empty());
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
    const nlohmann::json summary = nlohmann::json::parse(out);
    EXPECT_EQ(summary.at("out"), "out");
    EXPECT_EQ(summary.at("paths"), 3000);
    for (const char* key : {"seconds", "paths_per_second", "rays_per_second", "mean_depth",
                            "truncated_fraction", "m_exit_distance_median"})
        EXPECT_TRUE(summary.contains(key)) << key << " missing from " << out;
    EXPECT_EQ(summary.at("m_exit_distance_median").size(), 3u);

    // Nothing else was left in the test directory (no DIR.tmp.<pid>).
    EXPECT_EQ(listing(), std::vector<std::string>{"out"});
    std::vector<std::string> files;
    for (const auto& e : fs::directory_iterator(dir)) files.push_back(e.path().filename());
    std::sort(files.begin(), files.end());
    EXPECT_EQ(files, (std::vector<std::string>{"count.npy", "count_t.npy", "depth.npy",
                                               "exit_distance.npy", "exit_offset.npy", "meta.json",
                                               "p_t.npy", "ply.txt", "rdm_m.npy", "rdm_m_exit.npy",
                                               "rdm_r.npy", "truncated.npy"}));
}

TEST_F(GatherCliTest, MetaJsonAndPly) {
    gatherOk("--preset fleece " + kSmall + " --seed 7 --threads 2 --out out");
    const nlohmann::json m = meta("out");
    for (const char* key :
         {"paths", "seed", "bins", "threads", "elapsed_seconds", "paths_per_second",
          "rays_per_second", "truncated_fraction", "truncated_energy", "end_exit_fraction",
          "mean_depth", "versions", "fiber", "ply"})
        EXPECT_TRUE(m.contains(key)) << key << " missing from meta.json";
    EXPECT_EQ(m.at("paths"), 3000);
    EXPECT_EQ(m.at("seed"), 7);
    EXPECT_EQ(m.at("bins"), nlohmann::json({3, 8, 6, 12}));
    EXPECT_EQ(m.at("threads"), 2);
    EXPECT_EQ(m.at("material"), "fleece");
    EXPECT_GT(m.at("elapsed_seconds").get<double>(), 0.0);
    EXPECT_GT(m.at("paths_per_second").get<double>(), 0.0);
    EXPECT_GT(m.at("rays_per_second").get<double>(), 0.0);
    EXPECT_GT(m.at("mean_depth").get<double>(), 0.0);
    const double truncatedFraction = m.at("truncated_fraction").get<double>();
    EXPECT_GE(truncatedFraction, 0.0);
    EXPECT_LE(truncatedFraction, 1.0);
    ASSERT_TRUE(m.at("truncated_energy").is_array());
    EXPECT_EQ(m.at("truncated_energy").size(), 3u);
    EXPECT_TRUE(m.at("end_exit_fraction").is_number());
    // exit_distance: the M weight per channel is the histogram's, and the
    // quantiles are ordered.
    const auto exitHistogram = values<double>(readNpy(path("out/exit_distance.npy")));
    ASSERT_EQ(exitHistogram.size(), static_cast<size_t>(kExitDistanceBins + 1) * 3);
    const nlohmann::json& exit = m.at("exit_distance");
    for (int c = 0; c < 3; ++c) {
        double total = 0;
        for (int b = 0; b <= kExitDistanceBins; ++b) total += exitHistogram[b * 3 + c];
        EXPECT_NEAR(exit.at("m_weight")[c].get<double>(), total, 1e-12);
        EXPECT_GT(total, 0.0);
        EXPECT_LE(exit.at("median")[c].get<double>(), exit.at("p90")[c].get<double>());
    }
    EXPECT_TRUE(m.at("versions").at("weft").is_string());
    EXPECT_EQ(m.at("versions").at("weft"), WEFT_VERSION);
    EXPECT_TRUE(m.at("versions").at("embree").is_string());
    EXPECT_FALSE(m.at("versions").at("embree").get<std::string>().empty());
    // The fleece preset (paper Table 3).
    EXPECT_EQ(m.at("ply").at("fibers"), 300);
    EXPECT_DOUBLE_EQ(m.at("ply").at("density").get<double>(), 0.30);
    EXPECT_DOUBLE_EQ(m.at("ply").at("twist").get<double>(), 0.24);
    EXPECT_DOUBLE_EQ(m.at("fiber").at("beta_r_deg").get<double>(), 7.238);
    EXPECT_DOUBLE_EQ(m.at("fiber").at("gamma_tt_deg").get<double>(), 25.989);

    // The mean depth agrees with the depth histogram (no truncation at depth 1000 here).
    const auto depth = values<int64_t>(readNpy(path("out/depth.npy")));
    double depthSum = 0;
    for (size_t d = 0; d + 1 < depth.size(); ++d) depthSum += static_cast<double>(d) * depth[d];
    if (depth.back() == 0) {
        EXPECT_NEAR(m.at("mean_depth").get<double>(), depthSum / 3000, 1e-12);
    }

    // ply.txt: the 300 traced fiber centre lines, radius r = R sqrt(rho / N).
    const CurveSet ply = readCurves(path("out/ply.txt"));
    ASSERT_EQ(ply.curves.size(), 300u);
    const double r = std::sqrt(0.30 / 300);
    for (size_t i = 0; i < ply.curves.size(); ++i) {
        ASSERT_GE(ply.curves[i].points.size(), 2u) << i;
        ASSERT_FALSE(ply.curves[i].radii.empty()) << i;
        EXPECT_NEAR(ply.curves[i].radii[0], r, 1e-6) << i;
        for (const Vec3& p : ply.curves[i].points) {
            EXPECT_LE(std::hypot(p.x, p.y), 1.0 - r + 1e-6) << "curve " << i;
        }
    }
}

TEST_F(GatherCliTest, BitIdenticalForAnyThreadCount) {
    gatherOk("--preset fleece " + kSmall + " --seed 3 --threads 1 --out one");
    gatherOk("--preset fleece " + kSmall + " --seed 3 --threads 2 --out two");
    for (const char* name : kNpyFiles)
        EXPECT_TRUE(readFile(path("one") + "/" + name) == readFile(path("two") + "/" + name))
            << name << " differs between --threads 1 and --threads 2";
    EXPECT_TRUE(readFile(path("one/ply.txt")) == readFile(path("two/ply.txt")));
    EXPECT_TRUE(readFile(path("one/exit_distance.npy")) == readFile(path("two/exit_distance.npy")));
    EXPECT_EQ(meta("one").at("threads"), 1);
    EXPECT_EQ(meta("two").at("threads"), 2);
}

// `weft gather --shard K/N` and `weft gather merge`: the merge is the unsharded
// gather byte for byte (every array and ply.txt).
TEST_F(GatherCliTest, ShardsMergeToTheUnshardedGather) {
    gatherOk("--preset fleece " + kSmall + " --seed 3 --out whole");
    for (int k = 0; k < 4; ++k) {
        const std::string out = gatherOk(
            "--preset fleece " + kSmall + " --seed 3 --shard " + std::to_string(k) +
            "/4 --threads " + std::to_string(1 + k % 2) + " --out part" + std::to_string(k));
        EXPECT_TRUE(contains(out, "\"shard\": \"" + std::to_string(k) + "/4\"")) << out;
        EXPECT_EQ(meta("part" + std::to_string(k)).at("format"), "weft-gather-part");
    }
    const RunResult r = run("gather merge part3 part1 part0 part2 --out merged");
    ASSERT_EQ(r.status, 0) << r.err;
    for (const char* name : kNpyFiles)
        EXPECT_TRUE(readFile(path("whole") + "/" + name) == readFile(path("merged") + "/" + name))
            << name << " differs between the merged shards and the unsharded gather";
    EXPECT_TRUE(readFile(path("whole/ply.txt")) == readFile(path("merged/ply.txt")));
    EXPECT_TRUE(readFile(path("whole/exit_distance.npy")) ==
                readFile(path("merged/exit_distance.npy")));
    EXPECT_EQ(meta("merged").at("format"), "weft-gather");
    EXPECT_EQ(meta("merged").at("shards"), 4);
    EXPECT_EQ(meta("merged").at("paths"), 3000);
    EXPECT_EQ(meta("merged").at("mean_depth"), meta("whole").at("mean_depth"));
    // The merged directory is an ordinary gather; a part is not one.
    expectUserError(run("fit --rdm part0 --out m.json --quiet"), {"part0/meta.json", "merge"});

    // Sets of parts that are not one gather, and a damaged part: nothing is written.
    expectUserError(run("gather merge part0 part1 part3 --out bad"), {"missing", "2/4"});
    expectUserError(run("gather merge part0 part1 part1 part2 part3 --out bad"),
                    {"both shard 1/4"});
    gatherOk("--preset silk " + kSmall + " --seed 3 --shard 2/4 --out silk2");
    expectUserError(run("gather merge part0 part1 silk2 part3 --out bad"),
                    {"silk2/meta.json", "\"material\""});
    expectUserError(run("gather merge whole --out bad"), {"whole/meta.json", "not a shard"});
    const std::string bytes = readFile(path("part3/sum_m.npy"));
    writeText("part3/sum_m.npy", bytes.substr(0, bytes.size() - 100));
    expectUserError(run("gather merge part0 part1 part2 part3 --out bad"), {"part3/sum_m.npy"});
    for (const std::string& name : listing()) EXPECT_TRUE(name.rfind("bad", 0) != 0) << name;
    // Bad shards.
    expectUserError(gather("--preset fleece " + kSmall + " --shard 4/4 --out x"),
                    {"--shard", "4/4"});
    expectUserError(gather("--preset fleece --paths 3 --shard 0/4 --out x"), {"--shard", "N <= 3"});
    expectUserError(gather("--preset fleece " + kSmall + " --shard 1-4 --out x"),
                    {"--shard", "K/N"});
    expectUserError(gather("--preset fleece --out x"), {"--paths"});
}

TEST_F(GatherCliTest, AnyColourGatherRecoloursToAnyCTT) {
    gatherOk("--preset fleece " + kSmall + " --seed 3 --any-colour --out ac");
    const nlohmann::json m = meta("ac");
    EXPECT_EQ(m.at("any_colour"), true);
    const size_t rows = m.at("colour_paths").get<size_t>();
    EXPECT_GT(rows, 1000u);
    readChecked(path("ac"), "paths_bins.npy", "<i4", {rows, 3});
    readChecked(path("ac"), "paths_kind.npy", "|u1", {rows});
    readChecked(path("ac"), "paths_weight.npy", "<f4", {rows, 3});
    EXPECT_TRUE(m.at("arrays").contains("paths_weight"));

    // The gathered colour, from the records: byte for byte the gather's arrays.
    const RunResult same = run("gather recolour ac --c-tt 0.452,0.725,0.948 --out same");
    ASSERT_EQ(same.status, 0) << same.err;
    for (const char* name : kNpyFiles)
        EXPECT_TRUE(readFile(path("ac") + "/" + name) == readFile(path("same") + "/" + name))
            << name;
    EXPECT_FALSE(std::filesystem::exists(path("same/paths_bins.npy")));
    // The records do not keep exit points: no exit distances after a recolouring.
    EXPECT_FALSE(std::filesystem::exists(path("same/exit_distance.npy")));
    EXPECT_FALSE(meta("same").contains("exit_distance"));
    // Another colour: a gather of that colour, which weft fit reads as any other.
    ASSERT_EQ(run("gather recolour ac --c-tt 0.2,0.4,1 --out blue").status, 0);
    const nlohmann::json blue = meta("blue");
    EXPECT_EQ(blue.at("fiber").at("c_tt"), nlohmann::json({0.2, 0.4, 1.0}));
    EXPECT_EQ(blue.at("any_colour"), false);
    EXPECT_EQ(blue.at("recoloured_from").at("gather"), "ac");
    EXPECT_EQ(blue.at("mean_depth"), m.at("mean_depth"));
    EXPECT_FALSE(readFile(path("ac/rdm_m.npy")) == readFile(path("blue/rdm_m.npy")));

    // Shards of an any-colour gather merge to its records.
    for (int k = 0; k < 2; ++k)
        gatherOk("--preset fleece " + kSmall + " --seed 3 --any-colour --shard " +
                 std::to_string(k) + "/2 --out acpart" + std::to_string(k));
    ASSERT_EQ(run("gather merge acpart1 acpart0 --out acmerged").status, 0);
    for (const char* name : {"paths_bins.npy", "paths_kind.npy", "paths_weight.npy", "rdm_m.npy"})
        EXPECT_TRUE(readFile(path("ac") + "/" + name) == readFile(path("acmerged") + "/" + name))
            << name;
    gatherOk("--preset fleece " + kSmall + " --seed 3 --shard 0/2 --out plainpart0");
    expectUserError(run("gather merge acpart1 plainpart0 --out bad"), {"\"any_colour\" is false"});

    // Refused: an ordinary gather, bad colours, a missing gather, damaged records.
    gatherOk("--preset fleece " + kSmall + " --seed 3 --out plain");
    expectUserError(run("gather recolour plain --c-tt 0.5,0.5,0.5 --out bad"),
                    {"plain/meta.json", "not an any-colour gather", "--any-colour"});
    expectUserError(run("gather recolour ac --c-tt 1.5,0,0 --out bad"), {"--c-tt", "[0, 1]"});
    expectUserError(run("gather recolour ac --c-tt 0.5,0.5 --out bad"), {"--c-tt", "R,G,B"});
    expectUserError(run("gather recolour missing --c-tt 0.5,0.5,0.5 --out bad"), {"missing"});
    expectUserError(run("gather recolour ac --c-tt 0.5,0.5,0.5 --out ac"), {"--out"});
    const std::string bytes = readFile(path("ac/paths_weight.npy"));
    writeText("ac/paths_weight.npy", bytes.substr(0, bytes.size() - 7));
    expectUserError(run("gather recolour ac --c-tt 0.5,0.5,0.5 --out bad"),
                    {"ac/paths_weight.npy"});
    for (const std::string& name : listing()) EXPECT_TRUE(name.rfind("bad", 0) != 0) << name;
}

// weft gather family (docs/family.md): two shards into one folder make the
// family; each point is a gather folder the other commands read; bad options
// are exit 2 naming them.
TEST_F(GatherCliTest, FamilyShardsGatherTheYarnsOfTheBox) {
    for (const char* shard : {"0/2", "1/2"}) {
        const RunResult r = gather(std::string("family --points 3 --paths 400 --bins 3,8,6,12 "
                                               "--seed 2 --quiet --out fam --shard ") +
                                   shard);
        ASSERT_EQ(r.status, 0) << r.err;
        const nlohmann::json line = nlohmann::json::parse(r.out);
        EXPECT_EQ(line.at("shard"), shard);
        EXPECT_EQ(line.at("points_gathered"),
                  line.at("end_point").get<int>() - line.at("first_point").get<int>());
    }
    const nlohmann::json family = nlohmann::json::parse(readFile(path("fam/family.json")));
    ASSERT_EQ(family.at("yarns").size(), 3u);
    for (const nlohmann::json& yarn : family.at("yarns")) {
        const std::string folder = "fam/" + yarn.at("folder").get<std::string>();
        const nlohmann::json m = meta(folder);
        EXPECT_EQ(m.at("ply").at("fibers"), yarn.at("fibers"));
        EXPECT_EQ(m.at("fiber").at("c_r"), yarn.at("c_r"));
        EXPECT_TRUE(m.at("any_colour").get<bool>());
        EXPECT_EQ(run("gather recolour " + folder + " --c-tt 0.4,0.5,0.6 --out " +
                      yarn.at("folder").get<std::string>().substr(7))
                      .status,
                  0);
    }
    // A point is recorded for any colour: the fit asks for a recoloured gather.
    writeText("tiny.json", R"({"t_net": {"steps": 20, "restarts": 1, "batch": 64},
                               "m_net": {"hidden": [8], "steps": 20, "batch": 64}})");
    expectUserError(run("fit --rdm fam/points/00001 --config tiny.json --out m.json --quiet"),
                    {"fam/points/00001", "family gather", "weft gather recolour"});
    // A rerun keeps every point.
    const RunResult again = gather(
        "family --points 3 --paths 400 --bins 3,8,6,12 --seed 2 "
        "--quiet --out fam");
    ASSERT_EQ(again.status, 0) << again.err;
    EXPECT_EQ(nlohmann::json::parse(again.out).at("points_kept"), 3);
    writeText("box.json", R"({"fibers": [300, 200], "density": [0.2, 0.4], "twist": [0, 0.3],
        "beta_r_deg": [1, 8], "beta_tt_deg": [10, 28], "gamma_tt_deg": [19, 39], "c_r": [0, 1]})");
    expectUserError(gather("family --box box.json --points 3 --paths 400 --out bad"),
                    {"box.json", "fibers", "lo <= hi"});
    writeText("box.json", R"({"fibers": [200, 300], "density": [0.2, 1.5], "twist": [0, 0.3],
        "beta_r_deg": [1, 8], "beta_tt_deg": [10, 28], "gamma_tt_deg": [19, 39], "c_r": [0, 1]})");
    expectUserError(gather("family --box box.json --points 3 --paths 400 --out bad"),
                    {"box", "density", "(0, 1)"});
    expectUserError(gather("family --points 0 --paths 400 --out bad"), {"--points", "[1, 65536]"});
    expectUserError(gather("family --points 3 --paths 400 --shard 3/4 --out bad"), {"--shard"});
    expectUserError(gather("family --points 3 --paths 400 --seed 9 --out fam"),
                    {"fam/family.json", "another family"});
    expectUserError(gather("family --points 3 --paths 400 --box missing.json --out bad"),
                    {"missing.json"});
    // The edges design: recorded in family.json, read back, and not another seed's family.
    ASSERT_EQ(gather("family --points 2 --paths 400 --bins 3,8,6,12 --seed 2 --design edges "
                     "--quiet --out edges")
                  .status,
              0);
    const nlohmann::json edges = nlohmann::json::parse(readFile(path("edges/family.json")));
    EXPECT_EQ(edges.at("design"), "edges");
    EXPECT_FALSE(family.contains("design"));  // halton files stay as they were
    EXPECT_NE(edges.at("yarns")[0].at("density"), family.at("yarns")[0].at("density"));
    expectUserError(gather("family --points 2 --paths 400 --bins 3,8,6,12 --seed 2 --out edges"),
                    {"edges/family.json", "another family"});
    expectUserError(gather("family --points 2 --paths 400 --design grid --out bad"),
                    {"--design", "grid", "halton, edges"});
}

// ---------------------------------------------------------------------------
// Hostile gather files (issue 41, items 3 and 9): each reproducer ends in exit
// status 2, a message naming the file and the field or row, and nothing written.

// The elements of the array in `file`, rewritten after `change`.
template <typename T>
void rewriteNpy(const std::string& file, const std::function<void(std::vector<T>&)>& change) {
    const NpyArray a = readNpy(file);
    std::vector<T> v = values<T>(a);
    change(v);
    writeNpy(file, v.data(), a.shape);
}

// Item 3: a record's weight of 3e38 gave rdm_m.npy values of -13,664,891 with exit 0.
TEST_F(GatherCliTest, RecolourAndMergeRefuseWeightsTheFixedPointSumsCannotHold) {
    gatherOk("--preset fleece " + kSmall + " --seed 3 --any-colour --out ac");
    rewriteNpy<float>(path("ac/paths_weight.npy"),
                      [](std::vector<float>& w) { w[3 * 5 + 1] = 3e38f; });
    expectUserError(run("gather recolour ac --c-tt 0.5,0.5,0.5 --out bad"),
                    {"ac/paths_weight.npy", "row 5", "channel 1", "3e+38", "< 2^31"});
    // (A short fit, should the check ever be lost.)
    writeText("tiny.json", R"({"t_net": {"steps": 20, "restarts": 1, "batch": 64},
                               "m_net": {"hidden": [8], "steps": 20, "batch": 64}})");
    expectUserError(run("fit --rdm ac --out bad.json --config tiny.json --no-report "
                        "--colour-range 0.3,0.9 --quiet"),
                    {"ac/paths_weight.npy", "row 5"});
    for (int k = 0; k < 2; ++k)
        gatherOk("--preset fleece " + kSmall + " --seed 3 --any-colour --shard " +
                 std::to_string(k) + "/2 --out part" + std::to_string(k));
    rewriteNpy<float>(path("part1/paths_weight.npy"), [](std::vector<float>& w) { w[0] = 3e38f; });
    expectUserError(run("gather merge part0 part1 --out bad"),
                    {"part1/paths_weight.npy", "row 0", "< 2^31"});
    for (const std::string& name : listing()) EXPECT_TRUE(name.rfind("bad", 0) != 0) << name;
}

// Item 9: parts that disagree about the ply, lack their any_colour flag or
// their ply.txt, or share a file, were merged with exit 0.
TEST_F(GatherCliTest, MergeRefusesPartsThatAreNotShardsOfOneTracedGather) {
    for (int k = 0; k < 2; ++k)
        gatherOk("--preset fleece " + kSmall + " --seed 3 --shard " + std::to_string(k) +
                 "/2 --out p" + std::to_string(k));
    const std::string meta = readFile(path("p1/meta.json"));
    const auto merge = [&] { return run("gather merge p0 p1 --out bad"); };
    // Each field with one of the damages (gather_merge_test.cpp tries them all).
    for (const auto& [field, how] :
         std::initializer_list<std::pair<const char*, const char*>>{{"radius", "0"},
                                                                    {"segments", "-1"},
                                                                    {"period", "1e30"},
                                                                    {"fiber_radius", "removed"},
                                                                    {"radius", "string"}}) {
        nlohmann::json m = nlohmann::json::parse(meta);
        nlohmann::json& v = m.at("ply").at(field);
        if (how == std::string("removed"))
            m.at("ply").erase(field);
        else if (how == std::string("string"))
            v = v.dump();
        else
            v = v.get<double>() * std::stod(how);
        writeText("p1/meta.json", m.dump(2));
        SCOPED_TRACE(std::string(field) + " " + how);
        expectUserError(merge(), {"p1/meta.json", field});
    }
    writeText("p1/meta.json", meta);
    // ply.txt missing, or one digit of it changed.
    const std::string ply = readFile(path("p1/ply.txt"));
    fs::remove(path("p1/ply.txt"));
    expectUserError(merge(), {"p1/ply.txt"});
    std::string changed = ply;
    const size_t digit = changed.find_first_of("12345678", changed.size() / 3);
    changed[digit] = static_cast<char>(changed[digit] + 1);
    writeText("p1/ply.txt", changed);
    expectUserError(merge(), {"p1/ply.txt", "differs"});
    writeText("p1/ply.txt", ply);
    // p1/sum_m.npy a symbolic link to p0's.
    fs::rename(path("p1/sum_m.npy"), path("sum_m.npy"));
    fs::create_symlink("../p0/sum_m.npy", path("p1/sum_m.npy"));
    expectUserError(merge(), {"p1/sum_m.npy", "p0/sum_m.npy", "one file"});
    fs::remove(path("p1/sum_m.npy"));
    fs::rename(path("sum_m.npy"), path("p1/sum_m.npy"));
    // any_colour removed from every part of an any-colour gather.
    for (int k = 0; k < 2; ++k) {
        const std::string dir = "ac" + std::to_string(k);
        gatherOk("--preset fleece " + kSmall + " --seed 3 --any-colour --shard " +
                 std::to_string(k) + "/2 --out " + dir);
        nlohmann::json m = nlohmann::json::parse(readFile(path(dir + "/meta.json")));
        m.erase("any_colour");
        writeText(dir + "/meta.json", m.dump(2));
    }
    expectUserError(run("gather merge ac0 ac1 --out bad"), {"ac0/meta.json", "\"any_colour\""});
    for (const std::string& name : listing()) EXPECT_TRUE(name.rfind("bad", 0) != 0) << name;
    // The parts themselves merge.
    ASSERT_EQ(merge().status, 0);
}

// Item 9: weft fit read a gather with a damaged truncated.npy or depth.npy
// and succeeded.
TEST_F(GatherCliTest, FitRefusesADamagedTruncatedOrDepthArray) {
    gatherOk("--preset fleece " + kSmall + " --seed 3 --out g");
    writeText("tiny.json", R"({"t_net": {"steps": 20, "restarts": 1, "batch": 64},
                               "m_net": {"hidden": [8], "steps": 20, "batch": 64}})");
    const auto fit = [&] {
        return run("fit --rdm g --out m.json --config tiny.json --no-report --quiet");
    };
    const std::string truncated = readFile(path("g/truncated.npy")),
                      depth = readFile(path("g/depth.npy"));
    rewriteNpy<double>(path("g/truncated.npy"), [](std::vector<double>& t) { t[4] = NAN; });
    expectUserError(fit(), {"g/truncated.npy", "element 4 (0, 1, 1) is nan"});
    rewriteNpy<double>(path("g/truncated.npy"), [](std::vector<double>& t) { t[4] = -1; });
    expectUserError(fit(), {"g/truncated.npy", "element 4 (0, 1, 1) is -1"});
    writeText("g/truncated.npy", truncated.substr(0, truncated.size() - 8));
    expectUserError(fit(), {"g/truncated.npy", "truncated"});
    writeText("g/truncated.npy", truncated);
    rewriteNpy<int64_t>(path("g/depth.npy"), [](std::vector<int64_t>& d) { d[2] = -5; });
    expectUserError(fit(), {"g/depth.npy", "element 2 is -5"});
    writeText("g/depth.npy", depth);
    rewriteNpy<int64_t>(path("g/depth.npy"), [](std::vector<int64_t>& d) { d[2] += 1; });
    expectUserError(fit(), {"g/depth.npy", "3000 paths"});
    // A declared shape of 2^40 elements.
    std::string huge = depth;
    const size_t shape = huge.find("(1002,)");
    ASSERT_NE(shape, std::string::npos);
    huge.replace(shape, 7, "(1099511627776,)");
    huge.erase(huge.find('\n') - 9, 9);  // from the header's padding: its length stays
    writeText("g/depth.npy", huge);
    expectUserError(fit(), {"g/depth.npy", "1099511627776"});
    writeText("g/depth.npy", depth.substr(0, depth.size() - 8));
    expectUserError(fit(), {"g/depth.npy", "truncated"});
    writeText("g/depth.npy", depth);
    EXPECT_FALSE(fs::exists(path("m.json")));
    const RunResult ok = fit();
    EXPECT_EQ(ok.status, 0) << ok.err;
}

// A twist whose margin is many periods long needs more control points per
// fiber than an int holds (twist 1e6: 4e12): refused, not wrapped around.
TEST_F(GatherCliTest, ATwistTooLargeOrTooSmallForTheTracedPlyIsRefused) {
    writeText("fiber.json", kLosslessFiber);
    for (const char* twist : {"1e6", "1e300"})
        expectUserError(gather("--params fiber.json --fibers 5 --density 0.3 --twist " +
                               std::string(twist) + " " + kSmall + " --out x"),
                        {"points"});
    expectUserError(gather("--params fiber.json --fibers 5 --density 0.3 --twist 1e-310 " + kSmall +
                           " --out x"),
                    {"twist", "no finite twist period"});
    EXPECT_EQ(listing(), std::vector<std::string>{"fiber.json"});
}

TEST_F(GatherCliTest, SeedDeterminesTheResult) {
    gatherOk("--preset fleece " + kSmall + " --seed 11 --out a");
    gatherOk("--preset fleece " + kSmall + " --seed 11 --out b");
    gatherOk("--preset fleece " + kSmall + " --seed 12 --out c");
    for (const char* name : kNpyFiles)
        EXPECT_TRUE(readFile(path("a") + "/" + name) == readFile(path("b") + "/" + name))
            << name << " differs between two runs with the same seed";
    EXPECT_TRUE(readFile(path("a/rdm_m.npy")) != readFile(path("c/rdm_m.npy")))
        << "--seed 11 and --seed 12 gave the same rdm_m.npy";
    // The seed also places the fibers.
    EXPECT_TRUE(readFile(path("a/ply.txt")) != readFile(path("c/ply.txt")));
    EXPECT_EQ(meta("c").at("seed"), 12);
}

TEST_F(GatherCliTest, ParamsWithExplicitPly) {
    writeText("fiber.json", kLosslessFiber);
    gatherOk("--params fiber.json --fibers 40 --density 0.2 --twist 0.1 " + kSmall + " --out out");
    const nlohmann::json m = meta("out");
    EXPECT_EQ(m.at("ply").at("fibers"), 40);
    EXPECT_DOUBLE_EQ(m.at("ply").at("density").get<double>(), 0.2);
    EXPECT_DOUBLE_EQ(m.at("ply").at("twist").get<double>(), 0.1);
    EXPECT_EQ(m.at("material"), "fiber.json");
    EXPECT_DOUBLE_EQ(m.at("fiber").at("beta_tt_deg").get<double>(), 12.0);
    EXPECT_DOUBLE_EQ(m.at("fiber").at("gamma_tt_deg").get<double>(), 25.0);
    EXPECT_EQ(m.at("fiber").at("c_tt"), nlohmann::json({1.0, 1.0, 1.0}));
    EXPECT_EQ(readCurves(path("out/ply.txt")).curves.size(), 40u);
    int64_t paths = 0;
    for (int64_t c : values<int64_t>(readNpy(path("out/count.npy")))) paths += c;
    EXPECT_EQ(paths, 3000);
}

// Lossless fibers: every path's energy ends in T, R, M or the truncated
// remainder, so per incident bin p_t + sum_o (R + M) solidAngle(o) + truncated = 1.
void expectEnergyConserved(const std::string& dir) {
    const size_t ti = 3, pi = 8, to = 6, po = 12;
    const auto count = values<int64_t>(readChecked(dir, "count.npy", "<i8", {ti, pi}));
    const auto pT = values<double>(readChecked(dir, "p_t.npy", "<f8", {ti, pi}));
    const auto rdmR = values<float>(readChecked(dir, "rdm_r.npy", "<f4", {ti, pi, to, po, 3}));
    const auto rdmM = values<float>(readChecked(dir, "rdm_m.npy", "<f4", {ti, pi, to, po, 3}));
    const auto trunc = values<double>(readChecked(dir, "truncated.npy", "<f8", {ti, pi, 3}));
    const size_t nOut = to * po;
    for (size_t i = 0; i < ti * pi; ++i) {
        ASSERT_GT(count[i], 0) << "incident bin " << i << " received no paths";
        for (int c = 0; c < 3; ++c) {
            double total = pT[i] + trunc[i * 3 + c];
            for (size_t o = 0; o < nOut; ++o) {
                const double a = static_cast<double>(o / po) * kPi / to;
                const double b = static_cast<double>(o / po + 1) * kPi / to;
                const double solidAngle = (std::cos(a) - std::cos(b)) * 2 * kPi / po;
                const size_t cell = (i * nOut + o) * 3 + c;
                total += (static_cast<double>(rdmR[cell]) + rdmM[cell]) * solidAngle;
            }
            EXPECT_NEAR(total, 1.0, 1e-5) << "incident bin " << i << ", channel " << c;
        }
    }
}

TEST_F(GatherCliTest, LosslessFiberConservesEnergy) {
    writeText("fiber.json", kLosslessFiber);
    gatherOk("--params fiber.json --fibers 60 --density 0.3 --twist 0.2 " + kSmall + " --out out");
    expectEnergyConserved(path("out"));
}

TEST_F(GatherCliTest, LosslessFiberConservesEnergyWithTruncation) {
    writeText("fiber.json", kLosslessFiber);
    gatherOk("--params fiber.json --fibers 60 --density 0.3 --twist 0.2 " + kSmall +
             " --max-depth 2 --out out");
    expectEnergyConserved(path("out"));
    // Depth histogram 0, 1, 2, truncated; some paths are cut at depth 2.
    const auto depth = values<int64_t>(readChecked(path("out"), "depth.npy", "<i8", {4}));
    EXPECT_GT(depth[3], 0);
    const nlohmann::json m = meta("out");
    EXPECT_EQ(m.at("max_depth"), 2);
    EXPECT_NEAR(m.at("truncated_fraction").get<double>(), depth[3] / 3000.0, 1e-12);
    // Lossless: each truncated path carries its full unit weight.
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(m.at("truncated_energy")[c].get<double>(), depth[3] / 3000.0, 1e-6);
}

TEST_F(GatherCliTest, ReplacesAnExistingDirectory) {
    fs::create_directories(path("out"));
    writeText("out/old.txt", "old");
    gatherOk("--preset fleece " + kSmall + " --out out");
    EXPECT_FALSE(fs::exists(path("out/old.txt")));
    for (const char* name : kNpyFiles) EXPECT_TRUE(fs::is_regular_file(path("out") + "/" + name));
    EXPECT_TRUE(fs::is_regular_file(path("out/ply.txt")));
    EXPECT_TRUE(fs::is_regular_file(path("out/meta.json")));
    // Neither the temporary nor the moved-aside old directory is left behind.
    EXPECT_EQ(listing(), std::vector<std::string>{"out"});
}

// ---------------------------------------------------------------------------
// User errors: exit 2, a message naming the problem, no output left behind

TEST_F(GatherCliTest, ImpossiblePly) {
    writeText("fiber.json", kLosslessFiber);
    const RunResult r = gather(kImpossiblePly + " --out out");
    expectUserError(r, {"N=300", "rho=0.95"});
    EXPECT_EQ(listing(), std::vector<std::string>{"fiber.json"});
}

TEST_F(GatherCliTest, BadOptions) {
    struct Case {
        std::string args;
        std::vector<std::string> parts;
    };
    const std::string preset = "--preset fleece --quiet --out out ";
    const std::vector<Case> cases = {
        {preset + "--paths 0 --bins 3,8,6,12", {"paths", "0"}},
        {preset + "--paths -5 --bins 3,8,6,12", {"paths", "-5"}},
        {"--preset flece --paths 10 --out out", {"flece", "fleece", "silk", "gabardine"}},
        {preset + "--paths 10 --bins 22,90,45", {"--bins", "22,90,45"}},
        {preset + "--paths 10 --bins 0,90,45,90", {"bins", "theta_i", "0"}},
        {preset + "--paths 10 --bins 3,8,6,x", {"--bins", "3,8,6,x"}},
        {preset + "--paths 10 --bins 3,8,6,12 --max-depth 0", {"depth", "0"}},
        {preset + "--paths 10 --bins 3,8,6,12 --threads -1", {"threads", "-1"}},
        {preset + "--paths 10 --bins 3,8,6,12 --segments-per-twist 8", {"segments", "8"}},
        {"--preset fleece --fibers 40 --paths 10 --out out", {"--preset", "--fibers"}},
        {"--preset fleece --params fiber.json --paths 10 --out out", {"--preset", "--params"}},
        {"--params fiber.json --paths 10 --out out", {"--fibers"}},
        {"--params fiber.json --fibers 40 --density 0.2 --paths 10 --out out", {"--twist"}},
        {"--fibers 40 --density 0.2 --twist 0.1 --paths 10 --out out", {"--preset", "--params"}},
        {"--params bad.json --fibers 40 --density 0.2 --twist 0.1 --paths 10 --out out",
         {"bad.json", "malformed JSON"}},
        {"--params missing.json --fibers 40 --density 0.2 --twist 0.1 --paths 10 --out out",
         {"missing.json"}},
        {"--params fiber.json --fibers 40 --density 1.5 --twist 0.1 --paths 10 --out out",
         {"density", "1.5"}},
    };
    writeText("fiber.json", kLosslessFiber);
    writeText("bad.json", R"({"c_r":0.04, "c_tt":)");
    const std::vector<std::string> inputs = {"bad.json", "fiber.json"};
    for (const Case& c : cases) {
        SCOPED_TRACE("weft gather " + c.args);
        const RunResult r = gather(c.args);
        EXPECT_EQ(r.status, 2) << r.err;
        EXPECT_TRUE(contains(r.err, "weft: error: ")) << r.err;
        for (const std::string& p : c.parts)
            EXPECT_TRUE(contains(r.err, p)) << "stderr '" << r.err << "' lacks '" << p << "'";
        // No output directory and no out.tmp.<pid> left behind.
        EXPECT_EQ(listing(), inputs);
    }
}

TEST_F(GatherCliTest, OutputInsideAMissingDirectory) {
    const RunResult r = gather("--preset fleece " + kSmall + " --out nonexistent/sub/out");
    expectUserError(r, {"nonexistent/sub/out"});
    EXPECT_TRUE(listing().empty());
}

TEST_F(GatherCliTest, OutputIsARegularFile) {
    writeText("out", "not a directory");
    const RunResult r = gather("--preset fleece " + kSmall + " --out out");
    expectUserError(r, {"out", "not a directory"});
    EXPECT_EQ(readFile(path("out")), "not a directory");
    EXPECT_EQ(listing(), std::vector<std::string>{"out"});
}

TEST_F(GatherCliTest, FailedRunKeepsAnExistingDirectory) {
    fs::create_directories(path("out"));
    writeText("out/old.txt", "old");
    writeText("fiber.json", kLosslessFiber);
    const RunResult r = gather(kImpossiblePly + " --out out");
    expectUserError(r, {"N=300", "rho=0.95"});
    EXPECT_EQ(readFile(path("out/old.txt")), "old");
    EXPECT_EQ(listing(), (std::vector<std::string>{"fiber.json", "out"}));
}

}  // namespace
}  // namespace weft
