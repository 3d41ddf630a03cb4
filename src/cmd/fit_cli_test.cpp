// End-to-end tests of `weft fit`: a tiny gather, a short fit, the model file
// and the report it writes, and the errors for bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "cli_test_util.h"
#include "weft/core/file.h"
#include "weft/core/image_io.h"
#include "weft/core/npy.h"
#include "weft/yarn/yarn_model.h"

namespace weft {
namespace {

using testing::expectUserError;
using testing::RunResult;

// A fit that trains for a few hundred steps: enough to exercise every stage.
// 3 appearance nodes: the default 49 took most of a colour fit's time here
// (minutes under the sanitizers).
const char* const kShortConfig =
    R"({"t_net": {"steps": 200, "restarts": 2, "batch": 64},
        "m_net": {"hidden": [8, 8], "steps": 200, "batch": 64}, "appearance_nodes": 3})";

class FitCliTest : public testing::CliTestBase {
  protected:
    void SetUp() override {
        CliTestBase::SetUp();
        const RunResult g =
            run("gather --preset fleece --paths 4000 --bins 4,8,6,12 --seed 1 --quiet --out rdm");
        ASSERT_EQ(g.status, 0) << g.err;
        writeFileAtomic(path("short.json"), kShortConfig);
    }
};

// "exit_offset": true (docs/exit-point.md): the model carries the gather's
// exit offsets, each merged bin with its fine bins' share of the M weight
// within the table's range (summed here from exit_offset.npy itself); its M
// lobe is fitted in the exit frame (Fit.ExitOffsetModelsFitMInTheExitFrame).
TEST_F(FitCliTest, ExitOffsetTableComesFromTheGather) {
    writeFileAtomic(path("offsets.json"), R"({"t_net": {"steps": 100, "batch": 64},
        "m_net": {"hidden": [8, 8], "steps": 100, "batch": 64}, "exit_offset": true})");
    const RunResult r = run("fit --rdm rdm --out model.json --config offsets.json --quiet");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(readFile(path("model.json"))).at("version"), 5);
    const YarnModel model = loadYarnModel(path("model.json"));
    ASSERT_TRUE(model.exitOffset.has_value());
    const ExitOffsetTable& table = *model.exitOffset;
    const std::vector<double> h =
        npyToDoubles(readNpy(path("rdm/exit_offset.npy")), "exit_offset.npy");
    ASSERT_EQ(h.size(), kExitOffsetCells * kExitOffsetSlots * 3);
    const std::vector<double>& dz = table.edges().dz;
    int checked = 0;
    for (size_t cell = 0; cell < kExitOffsetCells; ++cell)
        for (int c = 0; c < 3; ++c) {
            // Per merged row of dz: the fine rows' weight, all the way round.
            std::vector<double> rows(dz.size() - 1, 0.0);
            double total = 0;
            for (int i = 0; i < kExitOffsetAxialBins; ++i) {
                const double z = (i + 0.5 - 0.5 * kExitOffsetAxialBins) * kExitOffsetAxialWidth;
                const size_t row = std::upper_bound(dz.begin(), dz.end(), z) - dz.begin() - 1;
                for (int j = 0; j < kExitOffsetAroundBins; ++j) {
                    const double w = h[(cell * kExitOffsetSlots +
                                        static_cast<size_t>(i) * kExitOffsetAroundBins + j) *
                                           3 +
                                       c];
                    rows[row] += w;
                    total += w;
                }
            }
            ASSERT_EQ(table.hasDensity(cell, c), total > 0) << cell << " " << c;
            if (!(total > 0)) continue;
            ++checked;
            for (size_t row = 0; row < rows.size(); ++row) {
                double p = 0;
                for (int j = 0; j < table.aroundBins(); ++j)
                    p += table.probability(cell, c, static_cast<int>(row), j);
                ASSERT_NEAR(p, rows[row] / total, 2e-5) << cell << " " << c << " " << row;
            }
        }
    EXPECT_GT(checked, 48);  // 4000 paths reach most cells in every channel
    // yarn check measures it against M in the exit frame too.
    ASSERT_EQ(run("yarn check --model model.json --rdm rdm --out check").status, 0);
    // Not for an ablation, nor from a gather without exit offsets.
    expectUserError(run("fit --rdm rdm --out x.json --config offsets.json --ablation naive "
                        "--no-report --quiet"),
                    {"exit_offset", "ablation"});
    std::filesystem::remove(path("rdm/exit_offset.npy"));
    expectUserError(run("fit --rdm rdm --out x.json --config offsets.json --no-report --quiet"),
                    {"rdm", "no exit_offset.npy", "gather again"});
}

TEST_F(FitCliTest, ColourRangeFitsAModelForAnyColour) {
    ASSERT_EQ(run("gather --preset fleece --paths 6000 --bins 4,8,6,12 --seed 1 --any-colour "
                  "--quiet --out ac")
                  .status,
              0);
    const RunResult r =
        run("fit --rdm ac --out any.json --config short.json --colour-range "
            "0.3,0.999 --colour-functions 3 --seed 3 --quiet");
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json summary = nlohmann::json::parse(r.out);
    EXPECT_EQ(summary.at("colour").at("functions"), 3);
    EXPECT_EQ(summary.at("colour").at("m_rel_l2_by_colour").size(), 8u);
    const YarnModel model = loadYarnModel(path("any.json"));
    ASSERT_TRUE(model.colour.has_value());
    EXPECT_EQ(model.colour->functions(), 3);
    EXPECT_EQ(model.mNet.widths(), (std::vector<int>{6, 8, 8, 9}));
    // Its energy calibration is by colour (version 3): none of one colour.
    EXPECT_TRUE(model.calibration.empty());
    ASSERT_EQ(model.colourCalibration.nodes.size(), 7u);
    EXPECT_EQ(model.colourCalibration.cTT.front(), 0.3);
    EXPECT_EQ(model.colourCalibration.cTT.back(), 0.999);
    // Version 4: with its appearance table (docs/colour.md, "Colour by appearance").
    EXPECT_EQ(nlohmann::json::parse(readFile(path("any.json"))).at("version"), 4);
    ASSERT_TRUE(model.appearance.has_value());
    EXPECT_EQ(model.appearance->cTT.size(), 3u);
    EXPECT_EQ(summary.at("colour").at("appearance").at("nodes"), 3);
    EXPECT_EQ(summary.at("colour").at("energy_calibration").at("nodes").size(), 7u);
    // It renders, checks and makes scenes like any model (at its gathered colour).
    ASSERT_EQ(run("yarn check --model any.json --rdm ac --out check").status, 0);
    // At another colour, against the RDM of that colour from the same walks.
    ASSERT_EQ(run("gather recolour ac --c-tt 0.5,0.6,0.7 --out grey").status, 0);
    ASSERT_EQ(run("yarn check --model any.json --rdm grey --c-tt 0.5,0.6,0.7 --out check2").status,
              0);
    // The calibration by colour brings the directional albedo at that colour
    // (between the nodes) closer to the recoloured gather's than the same
    // model without it.
    YarnModel uncalibrated = model;
    uncalibrated.colourCalibration = {};
    saveYarnModel(uncalibrated, path("raw.json"));
    for (const char* m : {"any", "raw"})
        ASSERT_EQ(run(std::string("yarn check --model ") + m +
                      ".json --rdm grey --c-tt 0.5,0.6,0.7 --min-paths 100 --out check-" + m)
                      .status,
                  0);
    auto albedoError = [&](const char* dir) {
        const nlohmann::json e = nlohmann::json::parse(readFile(path(dir) + "/check.json"))
                                     .at("albedo")
                                     .at("relative_error_mean_abs");
        return (e[0].get<double>() + e[1].get<double>() + e[2].get<double>()) / 3;
    };
    EXPECT_LT(albedoError("check-any"), albedoError("check-raw"));
    expectUserError(run("yarn check --model any.json --rdm grey --c-tt 0.5 --out check3"),
                    {"--c-tt", "R,G,B"});
    ASSERT_EQ(run("scene closeup --model any.json --width 12 --height 8 --out sc").status, 0);
    ASSERT_EQ(run("render sc/scene.json --spp 2 --quiet --out r.exr").status, 0);
    // A striped knit of two other colours (within the colour range), in neural mode.
    ASSERT_EQ(run("scene knit --model any.json --size 2 --colours 0.9,0.4,0.3 0.3,0.35,0.8 "
                  "--width 12 --height 8 --out striped")
                  .status,
              0);
    ASSERT_EQ(run("render striped/scene.json --mode neural --spp 2 --quiet --out s.exr").status, 0);

    expectUserError(run("fit --rdm rdm --out x.json --config short.json --colour-range 0.3,0.999"),
                    {"rdm/meta.json", "not an any-colour gather", "--any-colour"});
    expectUserError(run("fit --rdm ac --out x.json --colour-range 0.5,0.4"),
                    {"--colour-range", "0 < LO < HI <= 1"});
    expectUserError(run("fit --rdm ac --out x.json --colour-range 0.5"),
                    {"--colour-range", "LO,HI"});
    expectUserError(run("fit --rdm ac --out x.json --colour-range 0.3,0.9 --colour-functions 20"),
                    {"--colour-functions = 20"});
    expectUserError(run("fit --rdm ac --out x.json --colour-functions 4"),
                    {"--colour-functions needs --colour-range"});
    expectUserError(run("fit --rdm ac --out x.json --colour-range 0.3,0.9 --ablation naive"),
                    {"--colour-range", "--ablation"});
    // --recalibrate refits the calibration by colour from the recorded paths,
    // keeping the networks; an ordinary gather has none.
    const RunResult re =
        run("fit --recalibrate any.json --rdm ac --out re.json --config short.json "
            "--no-report --quiet");
    ASSERT_EQ(re.status, 0) << re.err;
    const YarnModel again = loadYarnModel(path("re.json"));
    EXPECT_TRUE(again.mNet == model.mNet);
    ASSERT_EQ(again.colourCalibration.nodes.size(), 7u);
    EXPECT_EQ(again.colourCalibration.nodes[3].m, model.colourCalibration.nodes[3].m);
    EXPECT_TRUE(again.fit.contains("recalibrated"));
    EXPECT_EQ(
        nlohmann::json::parse(re.out).at("colour").at("energy_calibration").at("nodes").size(), 7u);
    expectUserError(run("fit --rdm rdm --out x.json --recalibrate any.json"),
                    {"rdm/meta.json", "--any-colour"});
    EXPECT_FALSE(std::filesystem::exists(path("x.json")));
}

TEST_F(FitCliTest, WritesAValidModelAndItsReport) {
    const RunResult r = run("fit --rdm rdm --out model.json --config short.json --seed 3 --quiet");
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json summary = nlohmann::json::parse(r.out);
    EXPECT_EQ(summary.at("out"), "model.json");
    const YarnModel model = loadYarnModel(path("model.json"));
    EXPECT_EQ(model.tNet.widths(), (std::vector<int>{3, 7, 7, 1}));
    EXPECT_EQ(model.mNet.widths(), (std::vector<int>{6, 8, 8, 3}));
    EXPECT_EQ(model.ply.fibers, 300);
    EXPECT_NEAR(model.rLobe.tiltDeg, 37.01, 0.01);  // atan(pi * 0.24)
    EXPECT_EQ(model.rLobe.masking.size(), 4u);
    EXPECT_EQ(model.fit.at("rdm").at("paths"), 4000);
    for (const char* file :
         {"errors.json", "loss.png", "slice-m-theta45-phi000.png", "slice-r-theta75-phi090.png"})
        EXPECT_TRUE(std::filesystem::exists(path("model-report/") + file)) << file;
    const nlohmann::json errors = nlohmann::json::parse(readFile(path("model-report/errors.json")));
    EXPECT_DOUBLE_EQ(errors.at("m_rel_l2").get<double>(), model.fit.at("m_rel_l2").get<double>());

    // The same seed gives the same model at any thread count (the fit block's timings differ).
    ASSERT_EQ(run("fit --rdm rdm --out again.json --config short.json --seed 3 --threads 1 "
                  "--no-report --quiet")
                  .status,
              0);
    const YarnModel again = loadYarnModel(path("again.json"));
    EXPECT_TRUE(again.tNet == model.tNet);
    EXPECT_TRUE(again.mNet == model.mNet);
    EXPECT_EQ(again.rLobe.masking, model.rLobe.masking);
    EXPECT_EQ(again.sampling.gammaMDeg, model.sampling.gammaMDeg);
    EXPECT_FALSE(std::filesystem::exists(path("again-report")));
    EXPECT_EQ(again.calibration.r, model.calibration.r);

    // --recalibrate keeps the networks and R lobe and redoes steps 4-5 only;
    // on the same RDM and configuration that is the same calibration again.
    const RunResult re =
        run("fit --recalibrate again.json --rdm rdm --out re.json --config short.json "
            "--no-report --quiet");
    ASSERT_EQ(re.status, 0) << re.err;
    const YarnModel recalibrated = loadYarnModel(path("re.json"));
    EXPECT_TRUE(recalibrated.mNet == model.mNet);
    EXPECT_EQ(recalibrated.calibration.degree, model.calibration.degree);
    EXPECT_EQ(recalibrated.calibration.m, model.calibration.m);
    EXPECT_EQ(recalibrated.sampling.kappaR, model.sampling.kappaR);
    EXPECT_TRUE(recalibrated.fit.contains("recalibrated"));
    expectUserError(run("fit --recalibrate missing.json --rdm rdm --out re2.json --quiet"),
                    {"missing.json"});

    // The gather folder is recorded as given when relative, relative to the
    // current directory when absolute inside it, and by its name alone when
    // absolute elsewhere: never an absolute path of this machine
    // (docs/model-format.md, "fit").
    EXPECT_EQ(model.fit.at("rdm").at("path"), "rdm");
    EXPECT_EQ(recalibrated.fit.at("recalibrated").at("rdm"), "rdm");
    EXPECT_EQ(nlohmann::json::parse(readFile(path("model-report/errors.json"))).at("rdm"), "rdm");
    const std::string elsewhere = dir_.string() + "-elsewhere";
    for (const std::string& copy : {path("g16/cotton-rdm"), elsewhere + "/g16/cotton-rdm"}) {
        std::filesystem::create_directories(std::filesystem::path(copy).parent_path());
        std::filesystem::copy(path("rdm"), copy, std::filesystem::copy_options::recursive);
    }
    for (const auto& [rdm, recorded] :
         {std::pair<std::string, std::string>{path("g16/cotton-rdm"), "g16/cotton-rdm"},
          {elsewhere + "/g16/cotton-rdm", "cotton-rdm"},
          {"./g16/../g16/cotton-rdm/", "g16/cotton-rdm"}}) {
        const RunResult a = run("fit --recalibrate again.json --rdm " + rdm +
                                " --out abs.json --config short.json --no-report --quiet");
        ASSERT_EQ(a.status, 0) << a.err;
        const nlohmann::json record = loadYarnModel(path("abs.json")).fit;
        EXPECT_EQ(record.at("recalibrated").at("rdm"), recorded) << rdm;
        EXPECT_EQ(record.at("rdm").at("path"), "rdm");  // the original fit's, kept
    }
    std::filesystem::remove_all(elsewhere);
}

TEST_F(FitCliTest, ReferenceAddsNoiseFloor) {
    ASSERT_EQ(run("gather --preset fleece --paths 4000 --bins 4,8,6,12 --seed 2 --quiet --out ref")
                  .status,
              0);
    const RunResult r =
        run("fit --rdm rdm --reference ref --out m.json --config short.json --quiet");
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json errors = nlohmann::json::parse(readFile(path("m-report/errors.json")));
    const auto& floor = errors.at("reference").at("noise_floor");
    EXPECT_GT(floor.at("m_rel_l2").get<double>(), 0.0);
    EXPECT_GT(floor.at("t_rmse").get<double>(), 0.0);
}

TEST_F(FitCliTest, PrintConfigShowsDefaults) {
    const RunResult r = run("fit --print-config");
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json config = nlohmann::json::parse(r.out);
    EXPECT_EQ(config.at("t_net").at("hidden"), nlohmann::json({7, 7}));
    EXPECT_EQ(config.at("m_net").at("hidden"), nlohmann::json({21, 21, 21}));
}

TEST_F(FitCliTest, BadInputIsAClearError) {
    expectUserError(run("fit --rdm missing --out m.json"), {"missing"});
    expectUserError(run("fit --rdm rdm --out nowhere/m.json --config short.json"),
                    {"--out", "nowhere", "does not exist"});
    writeFileAtomic(path("bad.json"), R"({"m_net": {"stepz": 3}})");
    expectUserError(run("fit --rdm rdm --out m.json --config bad.json"), {"bad.json", "stepz"});
    writeFileAtomic(path("broken.json"), R"({"m_net": )");
    expectUserError(run("fit --rdm rdm --out m.json --config broken.json"),
                    {"broken.json", "malformed"});
    expectUserError(run("fit --out m.json"), {"--rdm"});
    std::filesystem::remove(path("rdm/rdm_m.npy"));
    expectUserError(run("fit --rdm rdm --out m.json --config short.json"), {"rdm_m.npy"});
    EXPECT_FALSE(std::filesystem::exists(path("m.json")));
}

// A network the renderer cannot run (yarn/network_capacity.h) is refused
// before any training: exit 2, the field and the limit named, and neither a
// model nor a report written. Without --quiet the fit prints a line per
// finished phase ("fit: R lobe (eq. 8) in ..."): none may appear. With
// energy_calibration_degree -1 such a fit used to train for minutes and then
// write a model that weft render refused.
TEST_F(FitCliTest, RefusesANetworkTheRendererCannotRunBeforeTraining) {
    const std::vector<std::pair<std::string, std::string>> cases = {
        {R"({"m_net": {"hidden": [128, 21], "steps": 200, "batch": 64}})",
         "wide.json: m_net.hidden = [128, 21] is out of range: the renderer's M network holds "
         "layers at most 64 wide"},
        {R"({"m_net": {"hidden": [65], "steps": 200, "batch": 64},
             "energy_calibration_degree": -1})",
         "wide.json: m_net.hidden = [65] is out of range: the renderer's M network holds layers "
         "at most 64 wide"},
        {R"({"t_net": {"hidden": [33], "steps": 200, "batch": 64}})",
         "wide.json: t_net.hidden = [33] is out of range: the renderer's T network holds layers "
         "at most 32 wide"},
        {R"({"t_net": {"hidden": [32, 32, 32], "steps": 200, "batch": 64}})",
         "the renderer's T network holds 2048 parameters"},
        {R"({"m_net": {"hidden": [4, 4, 4, 4, 4, 4, 4, 4]}})",
         "the renderer's M network holds at most 7 hidden layers"},
        {R"({"energy_calibration_degree": 13})",
         "wide.json: energy_calibration_degree = 13 is out of range: allowed [-1, 12]"}};
    for (const auto& [config, message] : cases) {
        writeFileAtomic(path("wide.json"), config);
        const RunResult r = run("fit --rdm rdm --out wide-model.json --config wide.json --seed 1");
        expectUserError(r, {message});
        EXPECT_FALSE(testing::contains(r.err, "fit: ")) << r.err;
        EXPECT_FALSE(std::filesystem::exists(path("wide-model.json"))) << config;
        EXPECT_FALSE(std::filesystem::exists(path("wide-model-report"))) << config;
    }
    // --recalibrate reads the configuration the same way.
    expectUserError(
        run("fit --recalibrate missing.json --rdm rdm --out re.json --config wide.json"),
        {"energy_calibration_degree = 13"});
}

// Networks at the evaluators' limits train, and the renderer loads the model:
// T 3-32-32-15-1 is exactly 2048 floats after padding, M 6-64-56-41-3 exactly
// 8192, and every layer of both is as wide as allowed or within one padded block.
TEST_F(FitCliTest, NetworksAtTheRenderersLimitsFitAndRender) {
    writeFileAtomic(path("limits.json"),
                    R"({"t_net": {"hidden": [32, 32, 15], "steps": 40, "restarts": 1, "batch": 64},
                        "m_net": {"hidden": [64, 56, 41], "steps": 40, "batch": 64}})");
    RunResult r = run("fit --rdm rdm --out model.json --config limits.json --no-report --quiet");
    ASSERT_EQ(r.status, 0) << r.err;
    const YarnModel model = loadYarnModel(path("model.json"));
    EXPECT_EQ(model.tNet.widths(), (std::vector<int>{3, 32, 32, 15, 1}));
    EXPECT_EQ(model.mNet.widths(), (std::vector<int>{6, 64, 56, 41, 3}));
    writeFileAtomic(path("yarn.txt"), "-0.2 0 0\n0 0.01 0\n0.2 0 0\n");
    writeFileAtomic(path("scene.json"), R"({
        "camera": {"from": [0, 0, 1], "to": [0, 0, 0], "fov_deg": 8},
        "film": {"width": 8, "height": 6},
        "render": {"spp": 2, "seed": 1},
        "yarns": [{"curves": "yarn.txt", "radius": 0.03, "plies": 3, "ply_twist": 0.3,
                   "model": "model.json"}]})");
    r = run("render scene.json --quiet --out limits.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_TRUE(std::filesystem::exists(path("limits.exr")));
}

// The ablations of paper Fig. 5 (docs/fit.md): fitted, written, rendered.
TEST_F(FitCliTest, AblationsFitAndRender) {
    expectUserError(
        run("fit --rdm rdm --out bogus.json --config short.json --ablation bogus --quiet"),
        {"--ablation", "bogus", "naive", "no-r-lobe"});
    EXPECT_FALSE(std::filesystem::exists(path("bogus.json")));

    RunResult r =
        run("fit --rdm rdm --out naive.json --config short.json --ablation naive --quiet");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out).at("ablation"), "naive");
    const YarnModel naive = loadYarnModel(path("naive.json"));
    EXPECT_EQ(naive.ablation, YarnAblation::Naive);
    EXPECT_EQ(naive.fit.at("ablation"), "naive");
    EXPECT_FALSE(naive.fit.contains("r_rel_l2"));
    EXPECT_EQ(naive.mNet.widths(), (std::vector<int>{6, 8, 8, 3}));  // the M network's architecture
    EXPECT_TRUE(std::filesystem::exists(path("naive-report/errors.json")));
    EXPECT_EQ(nlohmann::json::parse(readFile(path("naive.json"))).at("ablation"), "naive");

    r =
        run("fit --rdm rdm --out no-r.json --config short.json --ablation no-r-lobe --no-report "
            "--quiet");
    ASSERT_EQ(r.status, 0) << r.err;
    const YarnModel noR = loadYarnModel(path("no-r.json"));
    EXPECT_EQ(noR.ablation, YarnAblation::NoRLobe);
    EXPECT_EQ(noR.fit.at("ablation"), "no_r_lobe");
    EXPECT_TRUE(noR.rLobe.masking.empty());
    EXPECT_EQ(noR.sampling.kappaR, 0.0);

    // --recalibrate keeps the variant; --ablation with it is refused.
    r =
        run("fit --recalibrate naive.json --rdm rdm --out naive-re.json --config short.json "
            "--no-report --quiet");
    ASSERT_EQ(r.status, 0) << r.err;
    const YarnModel recalibrated = loadYarnModel(path("naive-re.json"));
    EXPECT_EQ(recalibrated.ablation, YarnAblation::Naive);
    EXPECT_TRUE(recalibrated.mNet == naive.mNet);
    expectUserError(run("fit --recalibrate naive.json --rdm rdm --out x.json --ablation naive "
                        "--quiet"),
                    {"--ablation", "--recalibrate"});

    // Both render with the ordinary yarn BSDF.
    writeFileAtomic(path("yarn.txt"), "-0.2 0 0\n0 0.01 0\n0.2 0 0\n");
    for (const std::string model : {"naive", "no-r"}) {
        writeFileAtomic(path(model + "-scene.json"), R"({
            "camera": {"from": [0, 0, 1], "to": [0, 0, 0], "fov_deg": 8},
            "film": {"width": 8, "height": 6},
            "render": {"spp": 2, "seed": 1},
            "yarns": [{"curves": "yarn.txt", "radius": 0.03, "plies": 3, "ply_twist": 0.3,
                       "model": ")" + path(model + ".json") +
                                                         R"("}]})");
        r = run("render " + model + "-scene.json --spp 2 --quiet --out " + model + "-render.exr");
        ASSERT_EQ(r.status, 0) << r.err;
        const Image image = readImage(path(model + "-render.exr"));
        double sum = 0;
        for (float v : image.pixels) {
            ASSERT_TRUE(std::isfinite(v)) << model;
            sum += v;
        }
        EXPECT_GT(sum, 0.0) << model;
    }
}

// weft fit family (docs/family.md): a family model with its energy
// calibration; --recalibrate refits only the calibration (here at another
// degree), keeping the networks; bad options are refused.
TEST_F(FitCliTest, FamilyFitsAndRecalibrates) {
    const RunResult defaults = run("fit family --print-config");
    ASSERT_EQ(defaults.status, 0) << defaults.err;
    const nlohmann::json config = nlohmann::json::parse(defaults.out);
    EXPECT_EQ(config.at("t_net").at("hidden"), nlohmann::json({16, 16}));
    EXPECT_EQ(config.at("m_net").at("hidden"), nlohmann::json({32, 32, 32}));
    EXPECT_EQ(config.at("energy_calibration_degree"), 6);
    ASSERT_EQ(run("gather family --points 3 --paths 3000 --bins 3,8,6,12 --seed 2 --quiet "
                  "--out fam")
                  .status,
              0);
    writeFileAtomic(path("family.json"),
                    R"({"t_net": {"steps": 200, "restarts": 1, "batch": 64},
                        "m_net": {"hidden": [8, 8], "steps": 200, "batch": 64},
                        "energy_calibration_degree": 2})");
    const RunResult r =
        run("fit family --gather fam --out f.json --config family.json "
            "--colour-functions 3 --quiet");
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json summary = nlohmann::json::parse(r.out);
    EXPECT_EQ(summary.at("calibration").at("degree"), 2);
    const nlohmann::json fitted = nlohmann::json::parse(readFile(path("f.json")));
    EXPECT_EQ(fitted.at("version"), 2);
    EXPECT_EQ(fitted.at("energy_calibration").at("degree"), 2);
    EXPECT_EQ(fitted.at("energy_calibration").at("r").size(), 9u);  // (2 + 1)^2 rows
    // R's calibration only by default: M's one node holds zeros.
    ASSERT_EQ(fitted.at("energy_calibration").at("c_tt").size(), 1u);
    for (const nlohmann::json& row : fitted.at("energy_calibration").at("m")[0])
        for (const nlohmann::json& v : row) EXPECT_EQ(v, 0.0);

    writeFileAtomic(path("degree1.json"), R"({"energy_calibration_degree": 1})");
    const RunResult re =
        run("fit family --gather fam --recalibrate f.json --config degree1.json "
            "--calibrate-m --out g.json --quiet");
    ASSERT_EQ(re.status, 0) << re.err;
    const nlohmann::json again = nlohmann::json::parse(readFile(path("g.json")));
    EXPECT_EQ(again.at("energy_calibration").at("degree"), 1);
    EXPECT_EQ(again.at("energy_calibration").at("c_tt").size(), 7u);  // M's nodes
    EXPECT_EQ(again.at("fit").at("recalibrated"), true);
    EXPECT_EQ(again.at("m_net"), fitted.at("m_net"));
    EXPECT_EQ(again.at("t_net"), fitted.at("t_net"));

    // Another box's gather; a missing model; a degree out of range.
    writeFileAtomic(path("box.json"),
                    R"({"fibers": [300, 400], "density": [0.2, 0.4], "twist": [0, 0.3],
                        "beta_r_deg": [1, 8], "beta_tt_deg": [10, 28], "gamma_tt_deg": [19, 39],
                        "c_r": [0, 1]})");
    ASSERT_EQ(run("gather family --points 2 --paths 1000 --bins 3,8,6,12 --seed 2 --quiet "
                  "--box box.json --out other")
                  .status,
              0);
    expectUserError(run("fit family --gather other --recalibrate f.json --out h.json --quiet"),
                    {"--recalibrate", "box"});
    expectUserError(run("fit family --gather fam --recalibrate missing.json --out h.json"),
                    {"missing.json"});
    writeFileAtomic(path("degree13.json"), R"({"energy_calibration_degree": 13})");
    expectUserError(run("fit family --gather fam --config degree13.json --out h.json"),
                    {"energy_calibration_degree", "13"});
}

}  // namespace
}  // namespace weft
