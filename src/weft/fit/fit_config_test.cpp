#include "weft/fit/fit_config.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "weft/core/test_util.h"
#include "weft/fit/fit.h"

namespace weft {
namespace {

void expectConfigError(const nlohmann::json& j, const std::string& message) {
    testing::expectInputError([&] { FitConfig::fromJson(j, "fit.json"); }, {message});
}

nlohmann::json hidden(const char* network, const std::vector<int>& widths) {
    return {{network, {{"hidden", widths}}}};
}

TEST(FitConfig, DefaultsRoundTripAndStrictKeys) {
    const FitConfig defaults;
    EXPECT_EQ(defaults.t.hidden, (std::vector<int>{7, 7}));
    const FitConfig again = FitConfig::fromJson(defaults.toJson(), "test");
    EXPECT_EQ(again.toJson(), defaults.toJson());
    const FitConfig partial = FitConfig::fromJson({{"m_net", {{"hidden", {21, 21}}}}}, "test");
    EXPECT_EQ(partial.m.hidden, (std::vector<int>{21, 21}));
    EXPECT_EQ(partial.m.steps, defaults.m.steps);
    expectConfigError({{"epochs", 3}},
                      "fit.json: unknown key \"epochs\" (allowed: t_net, m_net, jitter, masking, "
                      "threads, energy_calibration_degree, appearance_nodes, exit_offset)");
    EXPECT_FALSE(defaults.exitOffset);
    EXPECT_TRUE(FitConfig::fromJson({{"exit_offset", true}}, "test").exitOffset);
    expectConfigError({{"exit_offset", 1}}, "fit.json: exit_offset: expected");
    expectConfigError(
        {{"t_net", {{"epoch", 3}}}},
        "fit.json: t_net: unknown key \"epoch\" (allowed: hidden, steps, restarts, batch, "
        "learning_rate, final_learning_rate, loss)");
    expectConfigError({{"t_net", 3}}, "fit.json: t_net: expected an object, got 3");
    expectConfigError({{"m_net", {{"steps", 0}}}},
                      "fit.json: m_net.steps = 0 is out of range: allowed [1, 100000000]");
    expectConfigError(
        {{"m_net", {{"steps", 5.0}}}},
        "fit.json: m_net.steps: expected an integer in [1, 100000000], got 5 (written as "
        "a floating-point number)");
    // Beyond int: out of range, not wrapped round into it.
    expectConfigError({{"t_net", {{"restarts", 4294967297}}}},
                      "fit.json: t_net.restarts = 4294967297 is out of range: allowed [1, 64]");
    expectConfigError({{"m_net", {{"loss", "l1"}}}},
                      "fit.json: m_net.loss: expected one of \"mse\", \"log-mse\", got the string "
                      "\"l1\"");
    expectConfigError({{"t_net", {{"hidden", {7, 0}}}}},
                      "fit.json: t_net.hidden[1] = 0 is out of range: allowed [1, 4096]");
    expectConfigError({{"t_net", {{"hidden", nlohmann::json::array()}}}},
                      "fit.json: t_net.hidden: expected an array of 1 to 64 integers in [1, 4096] "
                      "(layer widths), got an array of 0");
    expectConfigError({{"t_net", {{"learning_rate", -1}}}},
                      "fit.json: t_net.learning_rate = -1 is out of range: allowed (0, 1]");
    expectConfigError({{"jitter", 1}}, "fit.json: jitter: expected true or false, got 1");
    expectConfigError({{"threads", 2000}},
                      "fit.json: threads = 2000 is out of range: allowed [0, 1024] (0: all cores)");
    expectConfigError(
        {{"energy_calibration_degree", -2}},
        "fit.json: energy_calibration_degree = -2 is out of range: allowed [-1, 12] (-1: "
        "off)");
    expectConfigError({{"appearance_nodes", 1}},
                      "fit.json: appearance_nodes = 1 is out of range: allowed [2, 257]");
    expectConfigError(nlohmann::json::array(), "fit.json: expected an object, got an array of 0");
}

// The renderer's evaluators hold T networks of layers up to 32 wide and 2048
// floats, M networks up to 64 wide and 8192 floats, each of at most 7 hidden
// layers, counting each layer's outputs padded to 16 (fixed_mlp.h). The counts
// below are worked out by hand: a hidden layer of `out` outputs after `in`
// inputs takes ceil16(out) * (in + 2) floats, the output layer ceil16(out) * (in + 1).
TEST(FitConfig, RefusesNetworksTheRendererCannotRun) {
    const std::string where = " (src/weft/yarn/network_capacity.h)";
    expectConfigError(hidden("m_net", {65}),
                      "fit.json: m_net.hidden = [65] is out of range: the renderer's M network "
                      "holds layers at most 64 wide" +
                          where);
    expectConfigError(hidden("m_net", {128, 21}),
                      "fit.json: m_net.hidden = [128, 21] is out of range: the renderer's M "
                      "network holds layers at most 64 wide" +
                          where);
    expectConfigError(hidden("t_net", {7, 33}),
                      "fit.json: t_net.hidden = [7, 33] is out of range: the renderer's T network "
                      "holds layers at most 32 wide" +
                          where);
    // Widths the M network would hold are still too wide for T.
    expectConfigError(hidden("t_net", {64}), "the renderer's T network holds layers at most 32");
    expectConfigError(hidden("t_net", {4, 4, 4, 4, 4, 4, 4, 4}),
                      "fit.json: t_net.hidden = [4, 4, 4, 4, 4, 4, 4, 4] is out of range: the "
                      "renderer's T network holds at most 7 hidden layers" +
                          where);
    expectConfigError(hidden("m_net", {8, 8, 8, 8, 8, 8, 8, 8}),
                      "the renderer's M network holds at most 7 hidden layers");
    // Every width fits, the parameters do not: 32*5 + 2 * 32*34 + 16*33 = 2864.
    expectConfigError(hidden("t_net", {32, 32, 32}),
                      "fit.json: t_net.hidden = [32, 32, 32] is out of range: the renderer's T "
                      "network holds 2048 parameters, each layer's outputs padded to a multiple "
                      "of 16, and 3-32-32-32-1 needs 2864" +
                          where);
    // 64*8 + 2 * 64*66 + 16*65 = 10000.
    expectConfigError(hidden("m_net", {64, 64, 64}), "6-64-64-64-3 needs 10000");
    // One padded block over: 160 + 1088 + 16*34 + 16*17 = 2064; 512 + 4224 + 48*58 + 16*43 = 8208.
    expectConfigError(hidden("t_net", {32, 32, 16}), "3-32-32-16-1 needs 2064");
    expectConfigError(hidden("m_net", {64, 56, 42}), "6-64-56-42-3 needs 8208");
    // A calibration degree that no model file may hold.
    expectConfigError({{"energy_calibration_degree", 13}},
                      "fit.json: energy_calibration_degree = 13 is out of range: allowed [-1, 12]");
}

TEST(FitConfig, AcceptsNetworksAtTheRenderersLimits) {
    const auto accepted = [](const nlohmann::json& j) {
        EXPECT_NO_THROW(FitConfig::fromJson(j, "fit.json")) << j.dump();
    };
    accepted(hidden("t_net", {32, 32}));
    accepted(hidden("t_net", {32, 32, 15}));  // 160 + 1088 + 16*34 + 16*16 = 2048 floats
    accepted(hidden("t_net", {4, 4, 4, 4, 4, 4, 4}));
    accepted(hidden("m_net", {64, 64}));
    accepted(hidden("m_net", {64, 56, 41}));  // 512 + 4224 + 48*58 + 16*42 = 8192 floats
    accepted(hidden("m_net", {1, 1, 1, 1, 1, 1, 1}));
    accepted({{"energy_calibration_degree", 12}});
    accepted({{"energy_calibration_degree", -1}});
    EXPECT_NO_THROW(FitConfig{}.validate("defaults"));
}

// A configuration made in code (the library, Python) is checked by the fit
// itself before it reads the gather: the RDM here is empty, and the message is
// the capacity's, not the gather's.
TEST(FitConfig, FitRefusesAnOversizedNetworkBeforeTraining) {
    FitConfig config;
    config.m.hidden = {65, 21};
    testing::expectInputError([&] { fitYarnModel(RdmData{}, config, 1, true); },
                              {"fit configuration: m_net.hidden = [65, 21] is out of range: the "
                               "renderer's M network holds layers at most 64 wide"});
    config = FitConfig{};
    config.t.hidden = {33};
    testing::expectInputError([&] { recalibrateYarnModel(YarnModel{}, RdmData{}, config, true); },
                              {"fit configuration: t_net.hidden = [33]"});
    config = FitConfig{};
    config.calibrationDegree = 13;
    testing::expectInputError([&] { fitYarnModel(RdmData{}, config, 1, true); },
                              {"fit configuration: energy_calibration_degree = 13"});
}

}  // namespace
}  // namespace weft
