// The yarn BSDF of every shipped and test model evaluates exactly as it did
// before the runtime model moved from fit/ to yarn/ (issue 16): values saved
// at commit cb1038a (tests/data/README.md says how) for fixed (wi, wo) pairs
// and sample inputs, compared bit for bit. A change that moves any of these
// numbers changes what the renderer draws: regenerate the file only for a
// deliberate change of the model, and say so.
#include <gtest/gtest.h>

#include <string>

#include "weft/core/json_file.h"
#include "weft/core/test_util.h"
#include "weft/yarn/yarn_bsdf.h"

namespace weft {
namespace {

Vec3 vec(const nlohmann::json& j) {
    return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

std::string modelPath(const std::string& file) {
    const std::string dir = file.find("-small") != std::string::npos ? "/tests/data/" : "/models/";
    return std::string(WEFT_SOURCE_DIR) + dir + file;
}

TEST(YarnBsdfValues, ShippedModelsEvaluateAsBefore) {
    const nlohmann::json saved =
        readJsonFile(std::string(WEFT_SOURCE_DIR) + "/tests/data/yarn-bsdf-values.json");
    ASSERT_EQ(saved.size(), 7u);
    int index = 0;
    for (const auto& [file, values] : saved.items()) {
        // Every third model under the (slow) sanitizers: each builds its tables.
        if (testing::sampleScale() < 1 && index++ % 3 != 0) continue;
        SCOPED_TRACE(file);
        const YarnBsdf bsdf = YarnBsdf::load(modelPath(file));
        for (const nlohmann::json& row : values.at("pairs")) {
            const Vec3 wi = vec(row.at("wi")), wo = vec(row.at("wo"));
            const Rgb f = bsdf.eval(wi, wo);
            for (int c = 0; c < 3; ++c)
                EXPECT_EQ(f[c], row.at("eval")[c].get<double>()) << wi << wo;
            EXPECT_EQ(bsdf.pdf(wi, wo), row.at("pdf").get<double>()) << wi << wo;
            EXPECT_EQ(bsdf.transmission(wi), row.at("p_t").get<double>()) << wi;
        }
        for (const nlohmann::json& row : values.at("samples")) {
            const Vec3 wi = vec(row.at("wi"));
            const auto& u = row.at("u");
            const BsdfSample s =
                bsdf.sample(wi, {u[0].get<double>(), u[1].get<double>(), u[2].get<double>()});
            EXPECT_EQ(s.lobe, row.at("lobe").get<int>()) << wi;
            EXPECT_EQ(s.pdf, row.at("pdf").get<double>()) << wi;
            EXPECT_EQ(s.wo, vec(row.at("wo"))) << wi;
            for (int c = 0; c < 3; ++c)
                EXPECT_EQ(s.weight[c], row.at("weight")[c].get<double>()) << wi;
        }
    }
}

}  // namespace
}  // namespace weft
