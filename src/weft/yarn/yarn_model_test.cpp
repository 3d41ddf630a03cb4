#include "weft/yarn/yarn_model.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/json_file.h"
#include "weft/core/rng.h"
#include "weft/core/test_util.h"
#include "weft/yarn/material_preset.h"

namespace weft {
namespace {

using nlohmann::json;
using testing::expectInputError;

// A model with every field away from its default, PReLU slopes and masking
// set, and a few awkward floats (-0, the smallest subnormal, the largest
// float, values with no short decimal form) among the weights.
YarnModel sampleModel() {
    YarnModel m;
    m.fiber = findMaterialPreset("fleece").fiber;
    m.ply = {300, 0.3, 0.24};
    m.tNet = NetworkWeights::initialised({3, 7, 7, 1}, OutputFunction::Sigmoid, 11);
    m.mNet = NetworkWeights::initialised({6, 21, 21, 21, 3}, OutputFunction::Exp, 12);
    Rng rng(3, 4);
    for (NetworkWeights* net : {&m.tNet, &m.mNet})
        for (NetworkLayer& layer : net->layers)
            for (float& slope : layer.prelu) slope = static_cast<float>(rng.uniform() - 0.2);
    auto& p = m.mNet.layers[0].weight;
    p[0] = -0.0f;
    p[1] = std::numeric_limits<float>::denorm_min();
    p[2] = std::numeric_limits<float>::max();
    p[3] = -std::numeric_limits<float>::max();
    p[4] = std::numeric_limits<float>::min();
    p[5] = 1.0f / 3.0f;
    p[6] = 16777217.0f;  // rounds to 2^24
    m.rLobe.tiltDeg = 37.0245;
    m.rLobe.masking = {0.42, 0.31, -0.125, 0.0625};
    m.sampling = {0.37, 12.5, 33.25, 0.81};
    m.calibration.degree = 2;
    for (int c = 0; c < 3; ++c) {
        m.calibration.r[c] = {0.1 * c, -0.2, 0.3, 1e-17, 0, -0.0, 0.5, 0.25, 1.0 / 3.0};
        m.calibration.m[c] = {-0.1, 0.2 * c, 0, 0, 0, 0, 0, 0, 0.7};
    }
    m.fit = {{"t_rmse", 0.0123},
             {"m_rel_l2", 0.21},
             {"r_rel_l2", 0.33},
             {"seconds", 61.5},
             {"rdm", {{"path", "rdm/fleece"}, {"seed", 7}, {"bins", {22, 90, 45, 90}}}}};
    return m;
}

// Bit for bit: the same shapes, PReLU flags, output function and parameters.
void expectSameNetwork(const NetworkWeights& a, const NetworkWeights& b) {
    ASSERT_EQ(a.widths(), b.widths());
    ASSERT_EQ(a.output, b.output);
    for (size_t l = 0; l < a.layers.size(); ++l) {
        const NetworkLayer &la = a.layers[l], &lb = b.layers[l];
        EXPECT_EQ(la.hasPrelu(), lb.hasPrelu()) << "layer " << l;
        for (const auto& [va, vb] :
             {std::pair{&la.weight, &lb.weight}, std::pair{&la.bias, &lb.bias},
              std::pair{&la.prelu, &lb.prelu}}) {
            ASSERT_EQ(va->size(), vb->size()) << "layer " << l;
            for (size_t k = 0; k < va->size(); ++k)
                ASSERT_EQ(std::bit_cast<uint32_t>((*va)[k]), std::bit_cast<uint32_t>((*vb)[k]))
                    << "layer " << l << " parameter " << k << ": " << (*va)[k] << " vs "
                    << (*vb)[k];
        }
    }
}

void expectSameModel(const YarnModel& a, const YarnModel& b) {
    EXPECT_EQ(a.fiber.toJson(), b.fiber.toJson());
    EXPECT_EQ(a.ply.fibers, b.ply.fibers);
    EXPECT_EQ(a.ply.density, b.ply.density);
    EXPECT_EQ(a.ply.twist, b.ply.twist);
    expectSameNetwork(a.tNet, b.tNet);
    expectSameNetwork(a.mNet, b.mNet);
    EXPECT_EQ(a.rLobe.tiltDeg, b.rLobe.tiltDeg);
    EXPECT_EQ(a.rLobe.masking, b.rLobe.masking);
    EXPECT_EQ(a.sampling.kappaR, b.sampling.kappaR);
    EXPECT_EQ(a.sampling.betaMDeg, b.sampling.betaMDeg);
    EXPECT_EQ(a.sampling.gammaMDeg, b.sampling.gammaMDeg);
    EXPECT_EQ(a.sampling.kappaM, b.sampling.kappaM);
    EXPECT_EQ(a.calibration.degree, b.calibration.degree);
    EXPECT_EQ(a.calibration.r, b.calibration.r);
    EXPECT_EQ(a.calibration.m, b.calibration.m);
    EXPECT_EQ(a.fit, b.fit);
}

// Expects yarnModelFromJson(j, "model.json") to fail with a message that
// starts with the source and contains every part (the JSON path at least).
void expectModelError(const json& j, std::initializer_list<std::string> parts) {
    try {
        yarnModelFromJson(j, "model.json");
        ADD_FAILURE() << "expected an InputError";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        EXPECT_EQ(msg.rfind("model.json: ", 0), 0u) << msg;
        for (const std::string& p : parts)
            EXPECT_NE(msg.find(p), std::string::npos)
                << "message '" << msg << "' lacks '" << p << "'";
    }
}

class YarnModelFile : public testing::TempDirTest {};

TEST_F(YarnModelFile, RoundTripIsBitExact) {
    const YarnModel model = sampleModel();
    const std::string file = path("model.json");
    saveYarnModel(model, file);
    const YarnModel back = loadYarnModel(file);
    expectSameModel(model, back);
    // Writing what was read gives the same bytes.
    saveYarnModel(back, path("again.json"));
    EXPECT_EQ(readFile(file), readFile(path("again.json")));
}

TEST_F(YarnModelFile, RoundTripWithoutMasking) {
    YarnModel model = sampleModel();
    model.rLobe.masking.clear();
    model.fit = json::object();
    saveYarnModel(model, path("model.json"));
    const YarnModel back = loadYarnModel(path("model.json"));
    expectSameModel(model, back);
    EXPECT_TRUE(back.rLobe.masking.empty());
}

TEST(YarnModel, JsonLayout) {
    const json j = yarnModelToJson(sampleModel());
    EXPECT_EQ(j.at("format"), "weft-yarn-model");
    EXPECT_EQ(j.at("version"), 1);
    EXPECT_EQ(j.at("ply").at("fibers"), 300);
    EXPECT_EQ(j.at("t_net").at("output"), "sigmoid");
    EXPECT_EQ(j.at("m_net").at("output"), "exp");
    ASSERT_EQ(j.at("m_net").at("layers").size(), 4u);
    const json& l1 = j.at("m_net").at("layers")[1];
    EXPECT_EQ(l1.at("weight").size(), 21u);
    EXPECT_EQ(l1.at("weight")[0].size(), 21u);
    EXPECT_EQ(l1.at("bias").size(), 21u);
    EXPECT_EQ(l1.at("prelu").size(), 21u);
    EXPECT_TRUE(j.at("m_net").at("layers")[3].at("prelu").is_null());
    EXPECT_EQ(j.at("r_lobe").at("masking").at("form"), "symmetric-quadratic");
    EXPECT_EQ(j.at("sampling").at("kappa_m"), 0.81);
    expectSameModel(sampleModel(), yarnModelFromJson(j, "memory"));
}

TEST_F(YarnModelFile, FileStartsWithFormatAndKeepsRowsOnOneLine) {
    saveYarnModel(sampleModel(), path("model.json"));
    const std::string text = readFile(path("model.json"));
    EXPECT_EQ(text.rfind("{\n  \"format\": \"weft-yarn-model\",\n  \"version\": 1,\n", 0), 0u)
        << text.substr(0, 200);
    EXPECT_EQ(text.back(), '\n');
    // 6-21-21-21-3 and 3-7-7-1: one line per weight row, not per number.
    const auto lines = std::count(text.begin(), text.end(), '\n');
    EXPECT_LT(lines, 300);
}

TEST(YarnModel, MissingKey) {
    json j = yarnModelToJson(sampleModel());
    j.erase("sampling");
    expectModelError(j, {"missing key \"sampling\""});
    j = yarnModelToJson(sampleModel());
    j["sampling"].erase("kappa_m");
    expectModelError(j, {"sampling: missing key \"kappa_m\""});
    j = yarnModelToJson(sampleModel());
    j["m_net"]["layers"][2].erase("prelu");
    expectModelError(j, {"m_net.layers[2]: missing key \"prelu\""});
    j = yarnModelToJson(sampleModel());
    j.erase("format");
    expectModelError(j, {"format", "weft-yarn-model"});
}

TEST(YarnModel, UnknownKey) {
    json j = yarnModelToJson(sampleModel());
    j["colour"] = 1;
    expectModelError(j, {"model.json: unknown key \"colour\" (allowed: format, version, ablation, "
                         "fiber, ply, t_net, m_net, r_lobe, sampling, energy_calibration, fit)"});
    j = yarnModelToJson(sampleModel());
    j["r_lobe"]["tilt"] = 10;
    expectModelError(j, {"r_lobe: unknown key \"tilt\""});
    j = yarnModelToJson(sampleModel());
    j["t_net"]["layers"][0]["scale"] = 1;
    expectModelError(j, {"t_net.layers[0]: unknown key \"scale\""});
    j = yarnModelToJson(sampleModel());
    j["ply"]["radius"] = 1;
    expectModelError(j, {"ply: unknown key \"radius\""});
    j = yarnModelToJson(sampleModel());
    j["fiber"]["beta"] = 1;
    expectModelError(j, {"model.json: fiber: unknown key \"beta\" (allowed: c_r, c_tt"});
    // The fit block is free-form.
    j = yarnModelToJson(sampleModel());
    j["fit"]["anything"] = {{"nested", {1, "two"}}};
    EXPECT_EQ(yarnModelFromJson(j, "model.json").fit.at("anything").at("nested")[1], "two");
}

TEST(YarnModel, WrongType) {
    json j = yarnModelToJson(sampleModel());
    j["version"] = "1";
    expectModelError(j, {"model.json: version: expected an integer, got the string \"1\""});
    j = yarnModelToJson(sampleModel());
    j["r_lobe"]["tilt_deg"] = "30";
    expectModelError(
        j, {"r_lobe.tilt_deg: expected a number in [0, 90) degrees, got the string \"30\""});
    j = yarnModelToJson(sampleModel());
    j["m_net"]["layers"][0]["weight"][2][1] = "0.5";
    expectModelError(j, {"m_net.layers[0].weight[2][1]: expected a number"});
    j = yarnModelToJson(sampleModel());
    j["ply"]["fibers"] = 300.5;
    expectModelError(j, {"ply.fibers: expected an integer in [1, 1000000], got 300.5"});
    j["ply"]["fibers"] = 300.0;  // an integer is written as one
    expectModelError(j, {"ply.fibers: expected an integer in [1, 1000000], got 300 (written as a "
                         "floating-point number)"});
    j = yarnModelToJson(sampleModel());
    j["fit"] = 3;
    expectModelError(j, {"model.json: fit: expected an object, got 3"});
    j = yarnModelToJson(sampleModel());
    j["t_net"]["output"] = 1;
    expectModelError(j,
                     {"t_net.output: expected one of \"sigmoid\", \"exp\", \"identity\", got 1"});
    expectModelError(
        json::array(),
        {"model.json: expected an object (a weft-yarn-model file), got an array of 0"});
}

TEST(YarnModel, WrongLayerShape) {
    json j = yarnModelToJson(sampleModel());
    j["m_net"]["layers"][1]["weight"][4].erase(0);
    expectModelError(j, {"m_net.layers[1].weight: expected 21 rows of 21 numbers", "row 4"});
    j = yarnModelToJson(sampleModel());
    j["m_net"]["layers"][3]["weight"].erase(0);
    expectModelError(j, {"m_net.layers[3].weight: expected 3 rows of 21 numbers",
                         "m_net has 3 outputs", "got 2 rows"});
    j = yarnModelToJson(sampleModel());
    j["m_net"]["layers"][1]["bias"].erase(0);
    expectModelError(j, {"m_net.layers[1].bias: expected an array of 21 numbers (one per row of "
                         "weight), got an array of 20"});
    j = yarnModelToJson(sampleModel());
    j["t_net"]["layers"][0]["prelu"].push_back(0.25);
    expectModelError(j, {"t_net.layers[0].prelu: expected an array of 7 numbers"});
    j = yarnModelToJson(sampleModel());
    j["t_net"]["layers"][1] = 3;
    expectModelError(j, {"model.json: t_net.layers[1]: expected an object, got 3"});
    j = yarnModelToJson(sampleModel());
    j["t_net"]["layers"] = json::array();
    expectModelError(j, {"t_net.layers: expected a non-empty array"});
}

TEST(YarnModel, ChainMismatch) {
    // Layer 1 has 20 rows: layer 2's 21 columns no longer chain onto it.
    json j = yarnModelToJson(sampleModel());
    j["m_net"]["layers"][1]["weight"].erase(20);
    j["m_net"]["layers"][1]["bias"].erase(20);
    j["m_net"]["layers"][1]["prelu"].erase(20);
    expectModelError(
        j, {"m_net.layers[2].weight: expected 21 rows of 20 numbers", "layers[1] has 20 outputs"});
}

TEST(YarnModel, NetworkInputsAndOutputs) {
    json j = yarnModelToJson(sampleModel());
    for (json& row : j["t_net"]["layers"][0]["weight"]) row.push_back(0.5);
    expectModelError(
        j, {"t_net.layers[0].weight: expected 7 rows of 3 numbers", "t_net has 3 inputs"});
    j = yarnModelToJson(sampleModel());
    j["t_net"]["layers"][2]["weight"].push_back(j["t_net"]["layers"][2]["weight"][0]);
    expectModelError(j, {"t_net.layers[2].weight", "t_net has 1 output)"});
    j = yarnModelToJson(sampleModel());
    // An m_net fed with wi alone.
    for (json& row : j["m_net"]["layers"][0]["weight"]) row = {row[0], row[1], row[2]};
    expectModelError(j, {"m_net.layers[0].weight", "m_net has 6 inputs"});
}

TEST(YarnModel, NonFiniteWeight) {
    json j = yarnModelToJson(sampleModel());
    j["t_net"]["layers"][1]["weight"][2][3] = std::numeric_limits<double>::quiet_NaN();
    expectModelError(j, {"t_net.layers[1].weight[2][3]: expected a finite number, got nan"});
    j = yarnModelToJson(sampleModel());
    j["m_net"]["layers"][0]["bias"][5] = -std::numeric_limits<double>::infinity();
    expectModelError(j, {"m_net.layers[0].bias[5]", "finite"});
    j = yarnModelToJson(sampleModel());
    j["m_net"]["layers"][2]["prelu"][0] = 1e39;  // finite double, infinite float
    expectModelError(j, {"m_net.layers[2].prelu[0]", "32-bit float"});
    j = yarnModelToJson(sampleModel());
    j["r_lobe"]["masking"]["coefficients"][2] = std::numeric_limits<double>::quiet_NaN();
    expectModelError(j, {"r_lobe.masking.coefficients[2]", "finite"});
}

TEST_F(YarnModelFile, SaveRefusesNonFiniteWeight) {
    YarnModel model = sampleModel();
    model.tNet.layers[0].weight[4] = std::numeric_limits<float>::quiet_NaN();
    expectInputError([&] { saveYarnModel(model, path("model.json")); },
                     {path("model.json"), "t_net.layers[0].weight[1][1]", "finite"});
    EXPECT_FALSE(std::filesystem::exists(path("model.json")));
}

TEST_F(YarnModelFile, NaNInTextIsAParseError) {
    saveYarnModel(sampleModel(), path("good.json"));
    std::string text = readFile(path("good.json"));
    const size_t at = text.find("\"bias\": [") + 9;
    text.replace(at, text.find(',', at) - at, "NaN");
    writeFileAtomic(path("model.json"), text);
    expectInputError([&] { loadYarnModel(path("model.json")); },
                     {path("model.json") + ":", ": malformed JSON"});
}

// model.json is parsed as strictly as scene.json (core/json_file.h).
TEST_F(YarnModelFile, DuplicateKeysAndOverflowingNumbersAreInputErrors) {
    saveYarnModel(sampleModel(), path("good.json"));
    const std::string text = readFile(path("good.json"));
    std::string duplicate = text;
    duplicate.insert(duplicate.find('{') + 1, "\"version\": 1, ");
    writeFileAtomic(path("model.json"), duplicate);
    expectInputError([&] { loadYarnModel(path("model.json")); },
                     {path("model.json"), "duplicate key \"version\""});
    std::string huge = text;
    const size_t at = huge.find("\"bias\": [") + 9;
    huge.replace(at, huge.find(',', at) - at, "1e400");
    writeFileAtomic(path("model.json"), huge);
    expectInputError([&] { loadYarnModel(path("model.json")); },
                     {path("model.json") + ":", "number overflow parsing '1e400'"});
}

// A weight that float can hold but whose products overflow it: refused at
// load, since no input could then be trusted to give a finite value (issue 18).
TEST(YarnModel, NetworksMustStayFiniteOverTheirDomain) {
    // sampleModel() stores float's extremes (a round-trip test): a file may.
    expectInputError([] { sampleModel().mNet.checkFiniteOnUnitInputs("m_net"); },
                     {"m_net.layers[0]: output 0 can reach", "allowed at most 1e30"});
    NetworkWeights t = NetworkWeights::initialised({3, 7, 7, 1}, OutputFunction::Sigmoid, 11);
    t.checkFiniteOnUnitInputs("t_net");
    t.layers[0].bias[0] = 1e20f;
    t.checkFiniteOnUnitInputs("t_net");
    t.layers[1].weight[0] = 1e20f;
    expectInputError([&] { t.checkFiniteOnUnitInputs("t_net"); },
                     {"t_net.layers[1]: output 0 can reach 1e+40"});
}

TEST(YarnModel, VersionAndFormat) {
    json j = yarnModelToJson(sampleModel());
    j["version"] = 6;
    expectModelError(j, {"version: unsupported version 6 (supported: 1 to 5)"});
    j["version"] = 0;
    expectModelError(j, {"version: unsupported version 0"});
    // Version 2 adds the optional "colour" block; without it a file reads the same.
    j["version"] = 2;
    EXPECT_NO_THROW(yarnModelFromJson(j, "model.json"));
    j = yarnModelToJson(sampleModel());
    j["format"] = "weft-fiber";
    expectModelError(j, {"format: expected \"weft-yarn-model\"", "weft-fiber"});
}

// Version 3 exists for a conditioned model's energy calibration by colour
// (docs/model-format.md): a version 3 file without its colour block was read
// as a model of one colour (issue 41). Version 2 without one still reads.
TEST(YarnModel, Version3NeedsItsColourBlock) {
    json j = yarnModelToJson(sampleModel());
    j["version"] = 3;
    expectModelError(j, {"model.json", "colour", "version 3"});
    j["version"] = 2;
    EXPECT_NO_THROW(yarnModelFromJson(j, "model.json"));
    EXPECT_NO_THROW(
        loadYarnModel(std::string(WEFT_SOURCE_DIR) + "/fuzz/seeds/model/conditioned-v3.json"));
}

// Version 5's exit-offset table (docs/exit-point.md): written only with the
// table, read back bit for bit; refused in an older version's file and in a
// colour-conditioned model.
TEST_F(YarnModelFile, ExitOffsetTableRoundTrips) {
    // One cell and channel with mass: a blob around dz = 0.5 in cell 9, red.
    std::vector<double> histogram(kExitOffsetCells * kExitOffsetSlots * 3, 0.0);
    for (int i = 60; i < 72; ++i)
        for (int j = 20; j < 40; ++j)
            histogram[(9 * kExitOffsetSlots + static_cast<size_t>(i) * kExitOffsetAroundBins + j) *
                      3] = 1.0 + (i + j) % 5;
    YarnModel model = sampleModel();
    model.exitOffset =
        ExitOffsetTable::fromHistogram(histogram, ExitOffsetTable::defaultEdges(), "test");
    saveYarnModel(model, path("model.json"));
    const json j = readJsonFile(path("model.json"));
    EXPECT_EQ(j.at("version"), 5);
    EXPECT_EQ(j.at("exit_offset").at("masses").size(), kExitOffsetCells);
    const YarnModel back = loadYarnModel(path("model.json"));
    expectSameModel(model, back);
    ASSERT_TRUE(back.exitOffset.has_value());
    EXPECT_EQ(back.exitOffset->toJson(), model.exitOffset->toJson());
    EXPECT_TRUE(back.exitOffset->hasDensity(9, 0));
    EXPECT_FALSE(back.exitOffset->hasDensity(9, 1));
    saveYarnModel(back, path("again.json"));
    EXPECT_EQ(readFile(path("model.json")), readFile(path("again.json")));
    // Without the table the writer stays at version 1.
    EXPECT_EQ(yarnModelToJson(sampleModel()).at("version"), 1);

    json older = j;
    older["version"] = 4;
    expectModelError(older, {"unknown key \"exit_offset\""});
    json bad = j;
    bad["exit_offset"]["masses"][9][0][3] = -1;
    expectModelError(bad, {"exit_offset.masses[9][0][3]", "integer in [0, 4294967295]"});
    json conditioned =
        readJsonFile(std::string(WEFT_SOURCE_DIR) + "/fuzz/seeds/model/conditioned-v3.json");
    conditioned["version"] = 5;
    conditioned["exit_offset"] = j.at("exit_offset");
    expectModelError(conditioned, {"exit_offset", "colour-conditioned"});
    // The fuzzer's seed of a version 5 file (4 x 2 bins) reads.
    const YarnModel seed =
        loadYarnModel(std::string(WEFT_SOURCE_DIR) + "/fuzz/seeds/model/exit-offset-v5.json");
    ASSERT_TRUE(seed.exitOffset.has_value());
    EXPECT_EQ(seed.exitOffset->axialBins(), 4);
    EXPECT_FALSE(seed.exitOffset->hasDensity(0, 0));
    EXPECT_TRUE(seed.exitOffset->hasDensity(0, 1));
}

TEST(YarnModel, OutOfRange) {
    const auto set = [](const char* block, const char* key, const json& value) {
        json j = yarnModelToJson(sampleModel());
        j[block][key] = value;
        return j;
    };
    expectModelError(set("r_lobe", "tilt_deg", 90), {"r_lobe.tilt_deg", "[0, 90)"});
    expectModelError(set("r_lobe", "tilt_deg", -1), {"r_lobe.tilt_deg", "[0, 90)"});
    expectModelError(set("sampling", "kappa_r", 1.5), {"sampling.kappa_r", "[0, 1]"});
    expectModelError(set("sampling", "beta_m_deg", 0), {"sampling.beta_m_deg", "(0, 90]"});
    expectModelError(set("sampling", "gamma_m_deg", 181), {"sampling.gamma_m_deg", "(0, 180]"});
    expectModelError(set("sampling", "kappa_m", -0.1), {"sampling.kappa_m", "[0, 1]"});
    expectModelError(set("ply", "density", 1.0), {"ply", "density", "(0, 1)"});
    expectModelError(set("ply", "fibers", 0), {"ply.fibers", "[1, 1000000]"});
    expectModelError(set("fiber", "beta_r_deg", 95), {"model.json: fiber", "beta_r_deg"});
    // Boundaries that are allowed.
    EXPECT_NO_THROW(yarnModelFromJson(set("sampling", "gamma_m_deg", 180), "model.json"));
    EXPECT_NO_THROW(yarnModelFromJson(set("r_lobe", "tilt_deg", 0), "model.json"));
}

TEST(YarnModel, Masking) {
    json j = yarnModelToJson(sampleModel());
    j["r_lobe"]["masking"]["coefficients"].erase(3);
    expectModelError(j, {"r_lobe.masking.coefficients: expected an array of 4 numbers, got an "
                         "array of 3"});
    j = yarnModelToJson(sampleModel());
    j["r_lobe"]["masking"]["form"] = "quadratic";
    expectModelError(j, {"r_lobe.masking.form: expected \"symmetric-quadratic\", got the string "
                         "\"quadratic\""});
    j = yarnModelToJson(sampleModel());
    j["r_lobe"]["masking"]["extra"] = 1;
    expectModelError(j, {"r_lobe.masking: unknown key \"extra\" (allowed: form, coefficients)"});
}

TEST(YarnModel, EnergyCalibration) {
    // Absent or null: no calibration (files written before it existed).
    json j = yarnModelToJson(sampleModel());
    j.erase("energy_calibration");
    EXPECT_TRUE(yarnModelFromJson(j, "model.json").calibration.empty());
    j["energy_calibration"] = nullptr;
    EXPECT_TRUE(yarnModelFromJson(j, "model.json").calibration.empty());
    j = yarnModelToJson(sampleModel());
    j["energy_calibration"]["degree"] = 13;
    expectModelError(j, {"energy_calibration.degree = 13 is out of range: allowed [0, 12]"});
    j["energy_calibration"]["degree"] = 2.5;
    expectModelError(j, {"energy_calibration.degree: expected an integer in [0, 12], got 2.5"});
    j = yarnModelToJson(sampleModel());
    j["energy_calibration"]["degree"] = 3;
    expectModelError(j, {"energy_calibration.r[0]: expected an array of 16 numbers ((degree + "
                         "1)^2), got an array of"});
    j = yarnModelToJson(sampleModel());
    j["energy_calibration"]["m"].erase(2);
    expectModelError(j, {"energy_calibration.m: expected 3 rows"});
    j = yarnModelToJson(sampleModel());
    j["energy_calibration"]["r"][1][4] = "nan";
    expectModelError(j, {"energy_calibration.r[1][4]: expected a number, got the string"});
    j = yarnModelToJson(sampleModel());
    j["energy_calibration"]["form"] = "table";
    expectModelError(j, {"energy_calibration.form: expected \"log-polynomial-sphere\""});
}

TEST(YarnModel, OutputFunction) {
    json j = yarnModelToJson(sampleModel());
    j["m_net"]["output"] = "relu";
    expectModelError(j, {"m_net.output", "relu", "sigmoid"});
    // A valid name is kept.
    j = yarnModelToJson(sampleModel());
    j["m_net"]["output"] = "identity";
    EXPECT_EQ(yarnModelFromJson(j, "model.json").mNet.output, OutputFunction::Identity);
}

TEST(YarnModel, SizeLimits) {
    json j = yarnModelToJson(sampleModel());
    json& layers = j["t_net"]["layers"];
    while (layers.size() < 17) layers.insert(layers.begin() + 1, layers[1]);
    expectModelError(j, {"t_net.layers: a network has at most 16 layers, got 17"});
    j = yarnModelToJson(sampleModel());
    j["t_net"]["layers"][0]["weight"] = json::array();
    for (int k = 0; k < 4097; ++k) j["t_net"]["layers"][0]["weight"].push_back({0, 0, 0});
    expectModelError(j, {"t_net.layers[0].weight: a layer has at most 4096 outputs"});
}

TEST_F(YarnModelFile, MissingFile) {
    expectInputError([&] { loadYarnModel(path("absent.json")); }, {path("absent.json")});
}

TEST_F(YarnModelFile, TruncatedFile) {
    saveYarnModel(sampleModel(), path("model.json"));
    const std::string text = readFile(path("model.json"));
    writeFileAtomic(path("model.json"), text.substr(0, text.size() / 2));
    expectInputError([&] { loadYarnModel(path("model.json")); },
                     {path("model.json") + ":", ": malformed JSON"});
    writeFileAtomic(path("model.json"), "");
    expectInputError([&] { loadYarnModel(path("model.json")); },
                     {path("model.json"), "malformed JSON"});
}

}  // namespace
}  // namespace weft
