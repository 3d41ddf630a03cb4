#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "weft/core/rng.h"
#include "weft/core/test_util.h"
#include "weft/fit/mlp.h"
#include "weft/yarn/fixed_mlp.h"
#include "weft/yarn/yarn_model.h"

namespace weft {
namespace {

// Random PReLU slopes (some negative, some above 1) so that both branches matter.
Mlp<float> randomNetwork(const std::vector<int>& widths, OutputFunction output, uint64_t seed) {
    Mlp<float> net(widths, output, seed);
    Rng rng(seed, 99);
    for (size_t l = 0; l + 1 < net.layers().size(); ++l) {
        auto slopes = net.preluSlopes(static_cast<int>(l));
        for (Eigen::Index k = 0; k < slopes.size(); ++k)
            slopes(k) = static_cast<float>(1.6 * rng.uniform() - 0.3);
    }
    return net;
}

// FixedMlp::forward against Mlp::forward on random inputs (unit-cube and
// wider values): the largest relative difference. For an identity output the
// difference is relative to max(|y|, 1): values near 0 come from cancelling
// sums whose own size sets the float rounding.
template <int W, int C>
double largestRelativeDifference(const Mlp<float>& net, const FixedMlp<W, C>& fixed, int count) {
    const double floor = net.output() == OutputFunction::Identity ? 1.0 : 1e-6;
    Rng rng(7, static_cast<uint64_t>(net.inputs()));
    Mlp<float>::Matrix x(net.inputs(), count);
    for (int c = 0; c < count; ++c)
        for (int r = 0; r < net.inputs(); ++r)
            x(r, c) =
                static_cast<float>(c % 2 ? 2.0 * rng.uniform() - 1.0 : 6.0 * rng.uniform() - 3.0);
    const Mlp<float>::Matrix y = net.forward(x);
    double worst = 0;
    std::vector<float> in(net.inputs()), out(net.outputs());
    for (int c = 0; c < count; ++c) {
        for (int r = 0; r < net.inputs(); ++r) in[r] = x(r, c);
        fixed.forward(in.data(), out.data());
        for (int r = 0; r < net.outputs(); ++r) {
            const double want = y(r, c), got = out[r];
            worst = std::max(worst, std::fabs(got - want) / std::max(std::fabs(want), floor));
        }
    }
    return worst;
}

TEST(FixedMlp, MatchesMlpForward) {
    struct Case {
        std::vector<int> widths;
        OutputFunction output;
    };
    const std::vector<Case> cases = {
        {{3, 7, 7, 1}, OutputFunction::Sigmoid},  {{6, 21, 21, 21, 3}, OutputFunction::Exp},
        {{6, 21, 21, 3}, OutputFunction::Exp},    {{6, 64, 64, 3}, OutputFunction::Exp},
        {{6, 1, 9, 3}, OutputFunction::Identity}, {{6, 3}, OutputFunction::Exp}};
    for (size_t k = 0; k < cases.size(); ++k) {
        const Mlp<float> net = randomNetwork(cases[k].widths, cases[k].output, 10 + k);
        const FixedMlp<64, 8192> fixed(net.weights(), "net");
        EXPECT_EQ(fixed.inputs(), cases[k].widths.front());
        EXPECT_EQ(fixed.outputs(), cases[k].widths.back());
        const double worst = largestRelativeDifference(net, fixed, 2000);
        EXPECT_LE(worst, 1e-5) << "case " << k;
        std::printf("case %zu: largest relative difference %.2g\n", k, worst);
    }
}

TEST(FixedMlp, MatchesMlpForwardOnCommittedModels) {
    for (const char* name : {"fleece-small", "gabardine-small"}) {
        const YarnModel model =
            loadYarnModel(std::string(WEFT_SOURCE_DIR) + "/tests/data/" + name + ".json");
        EXPECT_LE(largestRelativeDifference(Mlp<float>(model.tNet),
                                            TransmissionMlp(model.tNet, "t"), 2000),
                  1e-5)
            << name;
        EXPECT_LE(
            largestRelativeDifference(Mlp<float>(model.mNet), ScatteringMlp(model.mNet, "m"), 2000),
            1e-5)
            << name;
    }
}

TEST(FixedMlp, ExpOutputNeverOverflows) {
    Mlp<float> net({1, 1}, {false}, OutputFunction::Exp, 1);
    net.weight(0)(0, 0) = 1e30f;
    net.bias(0)(0) = 0;
    const FixedMlp<8, 64> fixed(net.weights(), "net");
    const float x = 1;
    float y = 0;
    fixed.forward(&x, &y);
    EXPECT_TRUE(std::isfinite(y));
    EXPECT_GT(y, 1e34f);
}

TEST(FixedMlp, RejectsNetworksThatDoNotFit) {
    testing::expectInputError(
        [] {
            FixedMlp<32, 4096>(NetworkWeights::initialised({6, 40, 3}, OutputFunction::Exp, 1),
                               "model.json: m_net");
        },
        {"model.json: m_net", "layers[0] is 40 x 6", "widths up to 32"});
    testing::expectInputError(
        [] {
            FixedMlp<32, 1024>(NetworkWeights::initialised({6, 32, 32, 3}, OutputFunction::Exp, 1),
                               "model.json: m_net");
        },
        {"model.json: m_net", "parameters", "1024"});
    testing::expectInputError(
        [] {
            FixedMlp<32, 8192>(NetworkWeights::initialised({3, 4, 4, 4, 4, 4, 4, 4, 4, 1},
                                                           OutputFunction::Sigmoid, 1),
                               "t_net");
        },
        {"t_net", "9 layers", "1 to 8"});
}

}  // namespace
}  // namespace weft
