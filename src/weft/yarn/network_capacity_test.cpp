#include "weft/yarn/network_capacity.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/test_util.h"
#include "weft/yarn/fixed_mlp.h"
#include "weft/yarn/network.h"

namespace weft {
namespace {

// Hand counts: a hidden layer of `out` outputs after `in` inputs takes
// ceil16(out) * (in + 2) floats (weights, bias, PReLU slope), the output layer
// ceil16(out) * (in + 1).
TEST(NetworkCapacity, PaddedParameterCountByHand) {
    EXPECT_EQ(paddedParameterCount({7, 7}, kTransmissionCapacity), 16 * 5 + 16 * 9 + 16 * 8);
    EXPECT_EQ(paddedParameterCount({21, 21, 21}, kScatteringCapacity),
              32 * 8 + 2 * 32 * 23 + 16 * 22);
    EXPECT_EQ(paddedParameterCount({32, 32, 15}, kTransmissionCapacity), 2048);
    EXPECT_EQ(paddedParameterCount({64, 56, 41}, kScatteringCapacity), 8192);
    EXPECT_EQ(paddedParameterCount({}, kTransmissionCapacity), 16 * 4);
}

// Whether the check accepts a set of hidden widths must agree with whether
// the renderer's evaluator (the FixedMlp that YarnBsdf holds) loads a
// network of that shape: the evaluator is the truth the check stands for.
template <typename Evaluator>
void expectCheckAgreesWithEvaluator(const NetworkCapacity& capacity,
                                    const std::vector<std::vector<int>>& cases) {
    for (const std::vector<int>& hidden : cases) {
        std::vector<int> widths = {capacity.inputs};
        widths.insert(widths.end(), hidden.begin(), hidden.end());
        widths.push_back(capacity.outputs);
        const NetworkWeights net = NetworkWeights::initialised(
            widths, capacity.outputs == 1 ? OutputFunction::Sigmoid : OutputFunction::Exp, 1);
        bool evaluatorLoads = true, checkAccepts = true;
        try {
            const Evaluator evaluator(net, "net");
        } catch (const InputError&) {
            evaluatorLoads = false;
        }
        try {
            checkHiddenWidths(hidden, capacity, "hidden");
        } catch (const InputError&) {
            checkAccepts = false;
        }
        EXPECT_EQ(checkAccepts, evaluatorLoads) << capacity.name << " " << net.widthsText();
    }
}

TEST(NetworkCapacity, CheckAgreesWithTheRenderersEvaluators) {
    expectCheckAgreesWithEvaluator<TransmissionMlp>(kTransmissionCapacity,
                                                    {{7, 7},
                                                     {32},
                                                     {33},
                                                     {32, 32},
                                                     {32, 32, 15},
                                                     {32, 32, 16},
                                                     {32, 32, 32},
                                                     {4, 4, 4, 4, 4, 4, 4},
                                                     {4, 4, 4, 4, 4, 4, 4, 4},
                                                     {16, 16, 16, 16, 16, 16, 16}});
    expectCheckAgreesWithEvaluator<ScatteringMlp>(kScatteringCapacity, {{21, 21, 21},
                                                                        {64},
                                                                        {65},
                                                                        {128, 21},
                                                                        {64, 64},
                                                                        {64, 56, 41},
                                                                        {64, 56, 42},
                                                                        {64, 64, 64},
                                                                        {8, 8, 8, 8, 8, 8, 8},
                                                                        {8, 8, 8, 8, 8, 8, 8, 8}});
}

TEST(NetworkCapacity, MessageNamesTheFieldTheLimitAndWhereItIsDefined) {
    testing::expectInputError(
        [] {
            checkHiddenWidths({128, 21}, kScatteringCapacity, "fit.json: m_net.hidden");
        },
        {"fit.json: m_net.hidden = [128, 21] is out of range: the renderer's M network holds "
         "layers at most 64 wide (src/weft/yarn/network_capacity.h)"});
    testing::expectInputError(
        [] {
            checkHiddenWidths({7, 0}, kTransmissionCapacity, "t");
        },
        {"t = [7, 0] is out of range: a layer is at least 1 wide"});
}

}  // namespace
}  // namespace weft
