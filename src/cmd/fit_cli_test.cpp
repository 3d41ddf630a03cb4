// End-to-end tests of `weft fit`: a tiny gather, a short fit, the model file
// and the report it writes, and the errors for bad input.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_test_util.h"
#include "weft/core/file.h"
#include "weft/fit/yarn_model.h"

namespace weft {
namespace {

using testing::expectUserError;
using testing::RunResult;

// A fit that trains for a few hundred steps: enough to exercise every stage.
const char* const kShortConfig =
    R"({"t_net": {"steps": 200, "restarts": 2, "batch": 64},
        "m_net": {"hidden": [8, 8], "steps": 200, "batch": 64}})";

class FitCliTest : public testing::CliTestBase {
protected:
    void SetUp() override {
        CliTestBase::SetUp();
        const RunResult g = run("gather --preset fleece --paths 4000 --bins 4,8,6,12 --seed 1 --quiet --out rdm");
        ASSERT_EQ(g.status, 0) << g.err;
        writeFileAtomic(path("short.json"), kShortConfig);
    }
};

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
    for (const char* file : {"errors.json", "loss.png", "slice-m-theta45-phi000.png",
                             "slice-r-theta75-phi090.png"})
        EXPECT_TRUE(std::filesystem::exists(path("model-report/") + file)) << file;
    const nlohmann::json errors = nlohmann::json::parse(readFile(path("model-report/errors.json")));
    EXPECT_DOUBLE_EQ(errors.at("m_rel_l2").get<double>(), model.fit.at("m_rel_l2").get<double>());

    // The same seed gives the same model at any thread count (the fit block's timings differ).
    ASSERT_EQ(run("fit --rdm rdm --out again.json --config short.json --seed 3 --threads 1 "
                  "--no-report --quiet")
                  .status,
              0);
    const YarnModel again = loadYarnModel(path("again.json"));
    EXPECT_EQ(again.tNet.parameters(), model.tNet.parameters());
    EXPECT_EQ(again.mNet.parameters(), model.mNet.parameters());
    EXPECT_EQ(again.rLobe.masking, model.rLobe.masking);
    EXPECT_EQ(again.sampling.gammaMDeg, model.sampling.gammaMDeg);
    EXPECT_FALSE(std::filesystem::exists(path("again-report")));
    EXPECT_EQ(again.calibration.r, model.calibration.r);

    // --recalibrate keeps the networks and R lobe and redoes steps 4-5 only;
    // on the same RDM and configuration that is the same calibration again.
    const RunResult re = run("fit --recalibrate again.json --rdm rdm --out re.json --config short.json "
                             "--no-report --quiet");
    ASSERT_EQ(re.status, 0) << re.err;
    const YarnModel recalibrated = loadYarnModel(path("re.json"));
    EXPECT_EQ(recalibrated.mNet.parameters(), model.mNet.parameters());
    EXPECT_EQ(recalibrated.calibration.degree, model.calibration.degree);
    EXPECT_EQ(recalibrated.calibration.m, model.calibration.m);
    EXPECT_EQ(recalibrated.sampling.kappaR, model.sampling.kappaR);
    EXPECT_TRUE(recalibrated.fit.contains("recalibrated"));
    expectUserError(run("fit --recalibrate missing.json --rdm rdm --out re2.json --quiet"),
                    {"missing.json"});
}

TEST_F(FitCliTest, ReferenceAddsNoiseFloor) {
    ASSERT_EQ(run("gather --preset fleece --paths 4000 --bins 4,8,6,12 --seed 2 --quiet --out ref").status, 0);
    const RunResult r = run("fit --rdm rdm --reference ref --out m.json --config short.json --quiet");
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
    expectUserError(run("fit --rdm rdm --out m.json --config broken.json"), {"broken.json", "malformed"});
    expectUserError(run("fit --out m.json"), {"--rdm"});
    std::filesystem::remove(path("rdm/rdm_m.npy"));
    expectUserError(run("fit --rdm rdm --out m.json --config short.json"), {"rdm_m.npy"});
    EXPECT_FALSE(std::filesystem::exists(path("m.json")));
}

}  // namespace
}  // namespace weft
