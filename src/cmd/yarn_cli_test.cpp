// End-to-end tests of `weft yarn eval | sample | check` against the library,
// on the committed small models (tests/data/README.md).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_test_util.h"
#include "weft/core/file.h"
#include "weft/core/npy.h"
#include "weft/core/rng.h"
#include "weft/yarn/yarn_bsdf.h"

namespace weft {
namespace {

using testing::expectUserError;
using testing::RunResult;

const std::string kFleece = std::string(WEFT_SOURCE_DIR) + "/tests/data/fleece-small.json";

class YarnCliTest : public testing::CliTestBase {
  protected:
    const YarnBsdf& bsdf() const {
        static const YarnBsdf b = YarnBsdf::load(kFleece);
        return b;
    }
};

Vec3 unitVector(Rng& rng) {
    const double z = 1 - 2 * rng.uniform(), phi = 2 * 3.141592653589793 * rng.uniform();
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
}

TEST_F(YarnCliTest, EvalMatchesTheLibrary) {
    Rng rng(1, 1);
    std::vector<double> pairs;
    const size_t rows = 200;
    for (size_t k = 0; k < rows; ++k) {
        const Vec3 wi = unitVector(rng), wo = unitVector(rng);
        for (const Vec3& v : {wi, wo}) pairs.insert(pairs.end(), {v.x, v.y, v.z});
    }
    writeNpy(path("pairs.npy"), pairs.data(), {rows, 6});
    const RunResult r = run("yarn eval --model " + testing::shellQuote(kFleece) +
                            " --in pairs.npy --out values.npy");
    ASSERT_EQ(r.status, 0) << r.err;
    const NpyMatrix values = readNpyMatrix(path("values.npy"), 3, "");
    ASSERT_EQ(values.rows, rows);
    for (size_t k = 0; k < rows; ++k) {
        const Vec3 wi{pairs[6 * k], pairs[6 * k + 1], pairs[6 * k + 2]};
        const Vec3 wo{pairs[6 * k + 3], pairs[6 * k + 4], pairs[6 * k + 5]};
        const Rgb f = bsdf().eval(wi, wo);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(values(k, c), f[c], 1e-12 * (1 + f[c])) << k;
    }
}

TEST_F(YarnCliTest, EvalRejectsBadInput) {
    const double notUnit[6] = {0, 0, 2, 0, 0, 1};
    writeNpy(path("bad.npy"), notUnit, {1, 6});
    expectUserError(
        run("yarn eval --model " + testing::shellQuote(kFleece) + " --in bad.npy --out v.npy"),
        {"bad.npy", "row 0", "wi", "not a unit vector"});
    const double good[6] = {0, 0, 1, 0, 0, 1};
    writeNpy(path("good.npy"), good, {1, 6});
    expectUserError(run("yarn eval --model missing.json --in good.npy --out v.npy"),
                    {"missing.json"});
    std::string text = readFile(kFleece);
    text.replace(text.find("\"version\": 1"), 12, "\"version\": 7");
    writeFileAtomic(path("v7.json"), text);
    expectUserError(run("yarn eval --model v7.json --in good.npy --out v.npy"),
                    {"v7.json", "version"});
    EXPECT_FALSE(std::filesystem::exists(path("v.npy")));
}

TEST_F(YarnCliTest, SampleRowsFollowTheContract) {
    const RunResult r = run("yarn sample --model " + testing::shellQuote(kFleece) +
                            " --wi 0.3,0.2,0.5 --count 3000 --seed 4 --out s.npy");
    ASSERT_EQ(r.status, 0) << r.err;
    const NpyMatrix s = readNpyMatrix(path("s.npy"), 8, "");
    ASSERT_EQ(s.rows, 3000u);
    const Vec3 wi = normalize(Vec3{0.3, 0.2, 0.5});
    int lobes[3] = {0, 0, 0};
    for (size_t k = 0; k < s.rows; ++k) {
        const Vec3 wo{s(k, 0), s(k, 1), s(k, 2)};
        const int lobe = static_cast<int>(s(k, 7));
        ASSERT_TRUE(lobe >= 0 && lobe <= 2) << k;
        ++lobes[lobe];
        if (lobe == YarnBsdf::kLobeT) {
            EXPECT_EQ(wo, -wi);
            EXPECT_EQ(s(k, 6), 0.0);
            for (int c = 0; c < 3; ++c) EXPECT_EQ(s(k, 3 + c), 1.0);
            continue;
        }
        const double pdf = bsdf().pdf(wi, wo);
        const Rgb f = bsdf().eval(wi, wo);
        EXPECT_NEAR(s(k, 6), pdf, 1e-9 * pdf);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(s(k, 3 + c), f[c] / pdf, 1e-9 * (1 + f[c] / pdf));
    }
    EXPECT_GT(lobes[1], 0);
    EXPECT_GT(lobes[2], 0);
    // Deterministic for a seed.
    ASSERT_EQ(run("yarn sample --model " + testing::shellQuote(kFleece) +
                  " --wi 0.3,0.2,0.5 --count 3000 --seed 4 --out again.npy")
                  .status,
              0);
    EXPECT_EQ(readFile(path("s.npy")), readFile(path("again.npy")));
    expectUserError(run("yarn sample --model " + testing::shellQuote(kFleece) +
                        " --wi 0,0,0 --count 10 --out x.npy"),
                    {"--wi", "non-zero"});
}

TEST_F(YarnCliTest, CheckWritesItsReport) {
    ASSERT_EQ(run("gather --preset fleece --paths 3000 --bins 4,8,6,12 --seed 1 --quiet --out rdm")
                  .status,
              0);
    const RunResult r = run("yarn check --model " + testing::shellQuote(kFleece) +
                            " --rdm rdm --min-paths 50 --threads 1 --out report");
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json line = nlohmann::json::parse(r.out);
    EXPECT_EQ(line.at("out"), "report");
    const nlohmann::json s = nlohmann::json::parse(readFile(path("report/check.json")));
    EXPECT_EQ(s.at("bins"), "4,8,6,12");
    EXPECT_EQ(s.at("bins_total"), 32);
    EXPECT_GT(s.at("bins_checked").get<int>(), 0);
    EXPECT_EQ(s.at("paths"), 3000);
    for (const char* key :
         {"relative_error_mean_abs", "relative_error_worst", "model_mean", "rdm_mean"})
        EXPECT_EQ(s.at("albedo").at(key).size(), 3u) << key;
    EXPECT_GT(s.at("m_rel_l2").get<double>(), 0.0);
    EXPECT_GT(s.at("r_rel_l2").get<double>(), 0.0);
    const auto& v = s.at("variance_proxy");
    EXPECT_GE(v.at("yarn").get<double>(), 1.0);
    EXPECT_GE(v.at("uniform_sphere").get<double>(), 1.0);
    for (const char* file : {"albedo_model.npy", "albedo_rdm.npy", "components_model.npy",
                             "components_rdm.npy", "second_moment.npy", "albedo.png",
                             "slice-m-theta45-phi000.png", "slice-r-theta75-phi090.png"})
        EXPECT_TRUE(std::filesystem::exists(path("report/") + file)) << file;
    const NpyArray albedo = readNpy(path("report/albedo_rdm.npy"));
    EXPECT_EQ(albedo.shape, (std::vector<size_t>{4, 8, 3}));
    EXPECT_FALSE(s.contains("dual_baseline"));

    // --dual: the dual-scattering baseline's errors beside the neural model's.
    const RunResult d = run("yarn check --model " + testing::shellQuote(kFleece) +
                            " --rdm rdm --min-paths 50 --threads 1 --dual --out report-dual");
    ASSERT_EQ(d.status, 0) << d.err;
    EXPECT_TRUE(nlohmann::json::parse(d.out).contains("dual_baseline"));
    const nlohmann::json dual =
        nlohmann::json::parse(readFile(path("report-dual/check.json"))).at("dual_baseline");
    for (const char* key : {"m_rel_l2", "r_rel_l2", "total_rel_l2", "neural_total_rel_l2"})
        EXPECT_GT(dual.at(key).get<double>(), 0.0) << key;
    EXPECT_EQ(dual.at("albedo").at("model_mean").size(), 3u);

    expectUserError(
        run("yarn check --model " + testing::shellQuote(kFleece) + " --rdm nowhere --out r2"),
        {"nowhere"});
    expectUserError(run("yarn check --model " + testing::shellQuote(kFleece) +
                        " --rdm rdm --threads -1 --out r2"),
                    {"--threads"});
    EXPECT_FALSE(std::filesystem::exists(path("r2")));
}

}  // namespace
}  // namespace weft
