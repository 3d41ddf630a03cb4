#include "weft/yarn/yarn_model.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <string_view>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/json_file.h"
#include "weft/core/json_message.h"
#include "weft/core/json_reader.h"
#include "weft/yarn/model_json.h"
#include "weft/yarn/yarn_lobes.h"

namespace weft {

namespace {

using nlohmann::json;

// Guards against absurd files (memory and time); far above the paper's 6-21-21-21-3.
constexpr int kMaxNetworkLayers = 16;
constexpr int kMaxNetworkWidth = 4096;
// The allowed parameter values, shared by the reader and validate().
const NumberRange kTiltRange = NumberRange::closedOpen(0, 90).with("degrees");
const NumberRange kUnitRange = NumberRange::closed(0, 1);
const NumberRange kBetaMRange = NumberRange::openClosed(0, 90).with("degrees");
const NumberRange kGammaMRange = NumberRange::openClosed(0, 180).with("degrees");
constexpr const char* kMaskingForm = "symmetric-quadratic";
constexpr const char* kCalibrationForm = "log-polynomial-sphere";
constexpr const char* kColourCalibrationForm = "log-polynomial-sphere-by-c-tt";

// "1 output", "3 outputs".
std::string plural(int n, const std::string& noun) {
    return std::to_string(n) + " " + noun + (n == 1 ? "" : "s");
}

// A number read by readJsonNumber that is also a finite float (network
// parameters are float32).
float floatNumber(double x, const std::string& source, const std::string& path) {
    if (std::fabs(x) > std::numeric_limits<float>::max())
        throwJsonError(
            source, path,
            "expected a finite 32-bit float, got " + formatNumber(x) + " (beyond +-3.4e38)");
    return static_cast<float>(x);
}
float floatNumber(const json& v, const std::string& source, const std::string& path) {
    return floatNumber(readJsonNumber(v, source, path), source, path);
}

std::vector<float> readVector(const JsonObjectReader& r, std::string_view key, int expected,
                              const std::string& why) {
    const std::vector<double> values = r.numbers(key, expected, {}, "(" + why + ")");
    std::vector<float> out(expected);
    for (int k = 0; k < expected; ++k)
        out[k] = floatNumber(values[k], r.source(), jsonIndexPath(r.pathOf(key), k));
    return out;
}

}  // namespace

// Reads a network {"layers": [...], "output": name} of `inputs` inputs and
// `outputs` outputs under the model's key `name` ("t_net").
NetworkWeights readModelNetwork(const JsonObjectReader& model, const std::string& name, int inputs,
                                int outputs) {
    const JsonObjectReader network = model.object(name, {"layers", "output"});
    const json& layers = network.value("layers");
    if (!layers.is_array() || layers.empty())
        network.fail("layers", "expected a non-empty array of layers, got " + describeJson(layers));
    if (layers.size() > static_cast<size_t>(kMaxNetworkLayers))
        network.fail("layers", "a network has at most " + std::to_string(kMaxNetworkLayers) +
                                   " layers, got " + std::to_string(layers.size()));
    std::vector<JsonObjectReader> layerReaders = network.objects("layers");

    NetworkWeights net;
    std::vector<NetworkLayer>& data = net.layers;
    for (size_t l = 0; l < layers.size(); ++l) {
        JsonObjectReader& layer = layerReaders[l];
        layer.allowKeys({"weight", "bias", "prelu"});
        const bool last = l + 1 == layers.size();
        // Shape: columns chain from the previous layer (or the network inputs);
        // the last layer's rows are the network outputs, a hidden layer's rows its width.
        const int in = l == 0 ? inputs : data.back().out;
        const std::string inWhy =
            l == 0 ? name + " has " + plural(inputs, "input")
                   : "layers[" + std::to_string(l - 1) + "] has " + plural(in, "output");
        const std::string weightPath = layer.pathOf("weight");
        const json& w = layer.value("weight");
        if (!w.is_array() || w.empty())
            layer.fail("weight", "expected a non-empty array of rows, got " + describeJson(w));
        if (w.size() > static_cast<size_t>(kMaxNetworkWidth))
            layer.fail("weight", "a layer has at most " + std::to_string(kMaxNetworkWidth) +
                                     " outputs, got " + std::to_string(w.size()) + " rows");
        const int out = last ? outputs : static_cast<int>(w.size());
        const std::string shape =
            "expected " + std::to_string(out) + " rows of " + std::to_string(in) + " numbers";
        if (last && w.size() != static_cast<size_t>(outputs))
            layer.fail("weight", shape + " (" + name + " has " + plural(outputs, "output") +
                                     "), got " + plural(static_cast<int>(w.size()), "row"));
        for (size_t row = 0; row < w.size(); ++row)
            if (!w[row].is_array() || w[row].size() != static_cast<size_t>(in))
                layer.fail("weight", shape + " (" + inWhy + "), got row " + std::to_string(row) +
                                         " = " + describeJson(w[row]));
        NetworkLayer d;
        d.in = in;
        d.out = out;
        d.weight.reserve(static_cast<size_t>(in) * out);
        for (int row = 0; row < out; ++row)
            for (int col = 0; col < in; ++col)
                d.weight.push_back(floatNumber(w[row][col], layer.source(),
                                               jsonIndexPath(jsonIndexPath(weightPath, row), col)));
        const std::string outWhy = "one per row of weight";
        d.bias = readVector(layer, "bias", out, outWhy);
        if (!layer.value("prelu").is_null()) d.prelu = readVector(layer, "prelu", out, outWhy + ", or null");
        data.push_back(std::move(d));
    }

    constexpr OutputFunction kOutputs[] = {OutputFunction::Sigmoid, OutputFunction::Exp,
                                           OutputFunction::Identity};
    net.output = kOutputs[network.oneOf(
        "output", {toString(kOutputs[0]), toString(kOutputs[1]), toString(kOutputs[2])})];
    return net;
}

json modelNetworkToJson(const NetworkWeights& net) {
    // Each float written as the double of the same value: the shortest
    // decimal form of that double parses back to it, and it to the float.
    auto numbers = [](const float* begin, size_t count) {
        json values = json::array();
        for (size_t k = 0; k < count; ++k) values.push_back(static_cast<double>(begin[k]));
        return values;
    };
    json layers = json::array();
    for (const NetworkLayer& layer : net.layers) {
        json rows = json::array();
        for (int row = 0; row < layer.out; ++row)
            rows.push_back(numbers(layer.weight.data() + static_cast<size_t>(row) * layer.in,
                                   static_cast<size_t>(layer.in)));
        layers.push_back({{"weight", std::move(rows)},
                          {"bias", numbers(layer.bias.data(), layer.bias.size())},
                          {"prelu", layer.hasPrelu()
                                        ? numbers(layer.prelu.data(), layer.prelu.size())
                                        : json(nullptr)}});
    }
    return {{"layers", std::move(layers)}, {"output", toString(net.output)}};
}

namespace {

PlyParams readPly(const JsonObjectReader& model) {
    const JsonObjectReader r = model.object("ply", {"fibers", "density", "twist"});
    PlyParams ply;
    ply.fibers = static_cast<int>(r.integer("fibers", {1, kMaxPlyFibers}));
    ply.density = r.number("density");
    ply.twist = r.number("twist");
    try {
        ply.validate();  // its messages start with "ply: "
    } catch (const InputError& e) {
        throw InputError(r.source() + ": " + e.what());
    }
    return ply;
}

RLobeParams readRLobe(const JsonObjectReader& model) {
    const JsonObjectReader r = model.object("r_lobe", {"tilt_deg", "masking"});
    RLobeParams p;
    p.tiltDeg = r.number("tilt_deg", kTiltRange);
    if (r.value("masking").is_null()) return p;
    const JsonObjectReader masking = r.object("masking", {"form", "coefficients"});
    masking.oneOf("form", {kMaskingForm});
    p.masking = masking.numbers("coefficients", kMaskingCoefficients);
    return p;
}

}  // namespace

std::vector<double> readCalibrationNodeColours(const JsonObjectReader& r) {
    const json& colours = r.value("c_tt");
    if (!colours.is_array() || colours.empty() ||
        colours.size() > static_cast<size_t>(ColourCalibration::kMaxNodes))
        r.fail("c_tt", "expected an array of 1 to " + std::to_string(ColourCalibration::kMaxNodes) +
                           " node colours, got " + describeJson(colours));
    std::vector<double> cTT;
    for (size_t g = 0; g < colours.size(); ++g)
        cTT.push_back(readJsonNumber(colours[g], r.source(), jsonIndexPath(r.pathOf("c_tt"), g)));
    return cTT;
}

SamplingParams readModelSampling(const JsonObjectReader& model) {
    const JsonObjectReader r =
        model.object("sampling", {"kappa_r", "beta_m_deg", "gamma_m_deg", "kappa_m"});
    SamplingParams p;
    p.kappaR = r.number("kappa_r", kUnitRange);
    p.betaMDeg = r.number("beta_m_deg", kBetaMRange);
    p.gammaMDeg = r.number("gamma_m_deg", kGammaMRange);
    p.kappaM = r.number("kappa_m", kUnitRange);
    return p;
}

json modelSamplingToJson(const SamplingParams& sampling) {
    return {{"kappa_r", sampling.kappaR},
            {"beta_m_deg", sampling.betaMDeg},
            {"gamma_m_deg", sampling.gammaMDeg},
            {"kappa_m", sampling.kappaM}};
}

namespace {

// Rows "r" and "m" of one calibration (3 channels of (degree + 1)^2 numbers)
// from `rows` at JSON path `path`.
void readCalibrationRows(const json& rows, const std::string& source, const std::string& path,
                         int degree, std::array<std::vector<double>, 3>* target) {
    const size_t terms = static_cast<size_t>(EnergyCalibration::termCount(degree));
    if (!rows.is_array() || rows.size() != 3)
        throwJsonError(source, path,
                       "expected 3 rows (R, G, B) of " + std::to_string(terms) + " numbers, got " +
                           describeJson(rows));
    for (size_t c = 0; c < 3; ++c) {
        const std::string rowPath = jsonIndexPath(path, c);
        if (!rows[c].is_array() || rows[c].size() != terms)
            throwJsonError(source, rowPath,
                           "expected an array of " + std::to_string(terms) +
                               " numbers ((degree + 1)^2), got " + describeJson(rows[c]));
        for (size_t k = 0; k < terms; ++k)
            (*target)[c].push_back(readJsonNumber(rows[c][k], source, jsonIndexPath(rowPath, k)));
    }
}

// null or absent (files written before it existed): none. The by-colour form
// (a conditioned model's, version 3) goes to *byColour.
EnergyCalibration readCalibration(const JsonObjectReader& model, bool conditioned, int64_t version,
                                  ColourCalibration* byColour) {
    EnergyCalibration cal;
    if (!model.has("energy_calibration") || model.isNull("energy_calibration")) return cal;
    const bool colourForm = conditioned && version >= 3;
    const JsonObjectReader r =
        colourForm ? model.object("energy_calibration", {"form", "degree", "c_tt", "r", "m"})
                   : model.object("energy_calibration", {"form", "degree", "r", "m"});
    r.oneOf("form", {colourForm ? kColourCalibrationForm : kCalibrationForm});
    const int degree = static_cast<int>(r.integer("degree", {0, EnergyCalibration::kMaxDegree}));
    if (!colourForm) {
        cal.degree = degree;
        readCalibrationRows(r.value("r"), r.source(), r.pathOf("r"), degree, &cal.r);
        readCalibrationRows(r.value("m"), r.source(), r.pathOf("m"), degree, &cal.m);
        return cal;
    }
    byColour->cTT = readCalibrationNodeColours(r);
    const size_t colours = byColour->cTT.size();
    byColour->nodes.resize(colours);
    for (const char* key : {"r", "m"}) {
        const json& perNode = r.value(key);
        if (!perNode.is_array() || perNode.size() != colours)
            r.fail(key, "expected one block of rows per node colour (" + std::to_string(colours) +
                            "), got " + describeJson(perNode));
        for (size_t g = 0; g < colours; ++g) {
            EnergyCalibration& node = byColour->nodes[g];
            node.degree = degree;
            readCalibrationRows(perNode[g], r.source(), jsonIndexPath(r.pathOf(key), g), degree,
                                key[0] == 'r' ? &node.r : &node.m);
        }
    }
    try {
        byColour->validate("energy_calibration");
    } catch (const InputError& e) {
        throw InputError(r.source() + ": " + e.what());
    }
    return cal;
}

// Key order of the written file: the layout order of docs/model-format.md
// (JSON objects are unordered; this is for the human reader). Keys not listed
// (the free-form "fit" block) follow in alphabetical order.
// clang-format off
constexpr std::array<std::string_view, 40> kKeyOrder = {
    "format",      "version",      "ablation", "box",        "fiber",      "ply",  "colour", "c_tt_range",
    "variable",    "t_net",
    "m_net",       "r_lobe",       "sampling", "energy_calibration", "degree", "r", "m", "fit",
    "layers",      "output",       "weight",   "bias",       "prelu",       "tilt_deg",
    "masking",     "form",         "coefficients", "fibers", "density",     "twist",
    "c_r",         "c_tt",         "beta_r_deg", "beta_tt_deg", "gamma_tt_deg", "kappa_r",
    "beta_m_deg",  "gamma_m_deg",  "kappa_m", "features"};
// clang-format on

std::vector<std::string> orderedKeys(const json& object, bool layoutOrder) {
    std::vector<std::string> keys;
    if (layoutOrder)
        for (std::string_view k : kKeyOrder)
            if (object.contains(k)) keys.emplace_back(k);
    for (const auto& item : object.items())
        if (std::find(keys.begin(), keys.end(), item.key()) == keys.end())
            keys.push_back(item.key());
    return keys;
}

// Pretty printer: objects and arrays of arrays one element per line, arrays
// of plain values (a weight row, a bias) on one line. Scalars use the
// library's own dump, so numbers keep their shortest round-trip form.
void writeValue(const json& v, int indent, bool layoutOrder, std::string& out) {
    const std::string pad(static_cast<size_t>(indent) + 2, ' ');
    if (v.is_object()) {
        if (v.empty()) {
            out += "{}";
            return;
        }
        out += "{\n";
        bool first = true;
        for (const std::string& key : orderedKeys(v, layoutOrder)) {
            out += first ? "" : ",\n";
            first = false;
            out += pad + json(key).dump() + ": ";
            writeValue(v.at(key), indent + 2, layoutOrder && key != "fit", out);
        }
        out += "\n" + std::string(static_cast<size_t>(indent), ' ') + "}";
    } else if (v.is_array()) {
        bool flat = true;
        for (const json& e : v) flat = flat && !e.is_structured();
        if (flat) {
            out += "[";
            for (size_t k = 0; k < v.size(); ++k) out += (k ? ", " : "") + v[k].dump();
            out += "]";
            return;
        }
        out += "[\n";
        for (size_t k = 0; k < v.size(); ++k) {
            out += (k ? ",\n" : "") + pad;
            writeValue(v[k], indent + 2, layoutOrder, out);
        }
        out += "\n" + std::string(static_cast<size_t>(indent), ' ') + "]";
    } else {
        out += v.dump();
    }
}

}  // namespace

std::string formatModelJson(const nlohmann::json& document) {
    std::string text;
    writeValue(document, 0, true, text);
    return text + "\n";
}

namespace {

YarnAblation readAblation(const JsonObjectReader& model) {
    constexpr YarnAblation kAblations[] = {YarnAblation::Naive, YarnAblation::NoRLobe};
    return kAblations[model.oneOf(
        "ablation", {yarnAblationName(kAblations[0]), yarnAblationName(kAblations[1])})];
}

}  // namespace

namespace {

void checkRange(double v, const NumberRange& range, const std::string& key) {
    if (!std::isfinite(v) || !range.contains(v))
        throw InputError(key + " = " + formatNumber(v) + " is out of range: allowed " +
                         range.text());
}

}  // namespace

void RLobeParams::validate() const {
    checkRange(tiltDeg, kTiltRange, "r_lobe.tilt_deg");
    if (!masking.empty() && masking.size() != kMaskingCoefficients)
        throw InputError("r_lobe.masking: expected " + std::to_string(kMaskingCoefficients) +
                         " coefficients, got " + std::to_string(masking.size()));
    for (size_t k = 0; k < masking.size(); ++k)
        checkRange(masking[k], NumberRange{}, "r_lobe.masking.coefficients[" + std::to_string(k) + "]");
}

void SamplingParams::validate() const {
    checkRange(kappaR, kUnitRange, "sampling.kappa_r");
    checkRange(betaMDeg, kBetaMRange, "sampling.beta_m_deg");
    checkRange(gammaMDeg, kGammaMRange, "sampling.gamma_m_deg");
    checkRange(kappaM, kUnitRange, "sampling.kappa_m");
}

namespace {

// An appearance table's ends are the colour range's, so that every colour
// the model takes has an appearance and no node lies outside.
void checkAppearanceSpansRange(const AppearanceTable& table, const ColourRange& range,
                               const std::string& what) {
    table.validate(what);
    if (std::fabs(table.cTT.front() - range.hi) > 1e-12 ||
        std::fabs(table.cTT.back() - range.lo) > 1e-12)
        throw InputError(what + ".c_tt: its nodes must span the colour range [" +
                         formatNumber(range.lo) + ", " + formatNumber(range.hi) +
                         "] from its bright end, got " + formatNumber(table.cTT.front()) + " to " +
                         formatNumber(table.cTT.back()));
}

}  // namespace

void YarnModel::validate() const {
    tNet.validate("t_net", 3, 1, OutputFunction::Sigmoid, "P(T|wi) must lie in [0, 1]");
    if (colour) {
        mNet.validate("m_net", 6, 3 * colour->functions(), OutputFunction::Identity,
                      "a conditioned model's colour functions combine its outputs before exp");
        if (ablation != YarnAblation::None || !calibration.empty())
            throw InputError("colour: a conditioned model has no ablation and no "
                             "energy_calibration of one colour");
        if (!colourCalibration.empty()) colourCalibration.validate("energy_calibration");
        if (appearance) checkAppearanceSpansRange(*appearance, colour->range(), "appearance");
    } else {
        mNet.validate("m_net", 6, 3, OutputFunction::Exp, "S_M must be non-negative");
        if (!colourCalibration.empty())
            throw InputError("energy_calibration: only a conditioned model has one by colour");
        if (appearance) throw InputError("appearance: only a colour model has an appearance table");
    }
    rLobe.validate();
    sampling.validate();
}

YarnModel YarnModel::forColour(const Rgb& cTT, const std::string& what) const {
    if (!colour)
        throw InputError(what + ": the model is fitted for one colour (C_TT " +
                         formatNumber(fiber.cTT.r) + ", " + formatNumber(fiber.cTT.g) + ", " +
                         formatNumber(fiber.cTT.b) +
                         "); for other colours fit it with weft fit --colour-range from a gather "
                         "made with --any-colour");
    const ColourRange& range = colour->range();
    for (int c = 0; c < 3; ++c)
        if (!(cTT[c] >= range.lo && cTT[c] <= range.hi))
            throw InputError(what + ": C_TT " + formatNumber(cTT[c]) +
                             " is out of this model's colour range [" + formatNumber(range.lo) +
                             ", " + formatNumber(range.hi) +
                             "] (weft fit --colour-range); give the yarn's \"appearance\" instead "
                             "to find a C_TT it reaches (docs/colour.md)");
    YarnModel m = *this;
    m.fiber.cTT = cTT;
    m.mNet = foldColourIntoNetwork(mNet, *colour, cTT);
    m.calibration = colourCalibration.at(cTT);
    m.colour.reset();
    m.colourCalibration = {};
    m.appearance.reset();
    return m;
}

Rgb YarnModel::ownColourInRange() const {
    if (!colour) return fiber.cTT;
    const ColourRange& range = colour->range();
    Rgb own = fiber.cTT;
    for (int c = 0; c < 3; ++c) own[c] = std::clamp(own[c], range.lo, range.hi);
    return own;
}

const char* yarnAblationName(YarnAblation ablation) {
    switch (ablation) {
        case YarnAblation::Naive:
            return "naive";
        case YarnAblation::NoRLobe:
            return "no_r_lobe";
        case YarnAblation::None:
            break;
    }
    return "none";
}

YarnAblation parseYarnAblation(const std::string& name, const std::string& what) {
    if (name.empty() || name == "none") return YarnAblation::None;
    if (name == "naive") return YarnAblation::Naive;
    if (name == "no-r-lobe") return YarnAblation::NoRLobe;
    throw InputError(what + " \"" + name +
                     "\": unknown ablation (allowed: naive, no-r-lobe, none)");
}

nlohmann::json yarnModelToJson(const YarnModel& model) {
    json masking = nullptr;
    if (!model.rLobe.masking.empty())
        masking = {{"form", kMaskingForm}, {"coefficients", model.rLobe.masking}};
    json calibration = nullptr;
    const ColourCalibration& byColour = model.colourCalibration;
    if (!model.calibration.empty()) {
        calibration = {{"form", kCalibrationForm},
                       {"degree", model.calibration.degree},
                       {"r", model.calibration.r},
                       {"m", model.calibration.m}};
    } else if (!byColour.empty()) {
        json r = json::array(), m = json::array();
        for (const EnergyCalibration& node : byColour.nodes) r.push_back(node.r), m.push_back(node.m);
        calibration = {{"form", kColourCalibrationForm},
                       {"degree", byColour.nodes[0].degree},
                       {"c_tt", byColour.cTT},
                       {"r", r},
                       {"m", m}};
    }
    // Version 1 for a model of one colour, 2 for a conditioned one, 3 when it
    // has an energy calibration by colour, 4 with an appearance table, 5 with
    // an exit-offset table: older readers refuse what they cannot read.
    const int version = model.exitOffset   ? 5
                        : model.appearance ? 4
                        : model.colour     ? (byColour.empty() ? 2 : 3)
                                           : 1;
    json document = {{"format", kYarnModelFormat},
                     {"version", version},
                     {"fiber", model.fiber.toJson()},
                     {"ply",
                      {{"fibers", model.ply.fibers},
                       {"density", model.ply.density},
                       {"twist", model.ply.twist}}},
                     {"t_net", modelNetworkToJson(model.tNet)},
                     {"m_net", modelNetworkToJson(model.mNet)},
                     {"r_lobe", {{"tilt_deg", model.rLobe.tiltDeg}, {"masking", masking}}},
                     {"sampling", modelSamplingToJson(model.sampling)},
                     {"energy_calibration", calibration},
                     {"fit", model.fit}};
    // Absent for the full model, so that its files stay as they were.
    if (model.ablation != YarnAblation::None)
        document["ablation"] = yarnAblationName(model.ablation);
    if (model.colour) document["colour"] = model.colour->toJson();
    if (model.appearance) document["appearance"] = model.appearance->toJson();
    if (model.exitOffset) document["exit_offset"] = model.exitOffset->toJson();
    return document;
}

YarnModel yarnModelFromJson(const nlohmann::json& j, const std::string& source) {
    if (!j.is_object())
        throwJsonError(source, "",
                       std::string("expected an object (a ") + kYarnModelFormat + " file), got " +
                           describeJson(j));
    JsonObjectReader r(j, source);
    // Format and version first: a file of another kind or version gets that
    // message rather than a list of unknown keys.
    if (!r.has("format"))
        r.fail(std::string("missing key \"format\" (expected \"") + kYarnModelFormat +
               "\": not a weft yarn model?)");
    r.oneOf("format", {kYarnModelFormat});
    const int64_t version = r.integer("version");
    if (version < 1 || version > kYarnModelVersion)
        r.fail("version", "unsupported version " + describeJson(r.value("version")) +
                              " (supported: 1 to " + std::to_string(kYarnModelVersion) + ")");
    // energy_calibration may be absent (files written before it existed);
    // ablation is absent for the full model; colour needs version 2.
    if (version >= 5)
        r.allowKeys({"format", "version", "ablation", "fiber", "ply", "t_net", "m_net", "r_lobe",
                     "sampling", "energy_calibration", "fit", "colour", "appearance",
                     "exit_offset"});
    else if (version >= 4)
        r.allowKeys({"format", "version", "ablation", "fiber", "ply", "t_net", "m_net", "r_lobe",
                     "sampling", "energy_calibration", "fit", "colour", "appearance"});
    else if (version >= 2)
        r.allowKeys({"format", "version", "ablation", "fiber", "ply", "t_net", "m_net", "r_lobe",
                     "sampling", "energy_calibration", "fit", "colour"});
    else
        r.allowKeys({"format", "version", "ablation", "fiber", "ply", "t_net", "m_net", "r_lobe",
                     "sampling", "energy_calibration", "fit"});

    YarnModel model;
    model.fiber = FiberParams::fromJson(r.value("fiber"), source, "fiber");
    model.ply = readPly(r);
    model.tNet = readModelNetwork(r, "t_net", 3, 1);
    // Versions 3 and 4 exist for a conditioned model's calibration by colour
    // and appearance table: the writer writes them only with a colour block,
    // which they require (version 5 is for the exit-offset table, of a model
    // of one colour).
    if ((version == 3 || version == 4) && !r.has("colour"))
        r.fail("colour", "missing: a version " + std::to_string(version) +
                             " model is a colour-conditioned one (its energy_calibration by "
                             "colour); a model of one colour is version 1");
    if (version >= 2 && r.has("colour"))
        model.colour = ColourBasis::fromJson(r.value("colour"), source + ": colour");
    model.mNet = readModelNetwork(r, "m_net", 6, model.colour ? 3 * model.colour->functions() : 3);
    model.rLobe = readRLobe(r);
    model.sampling = readModelSampling(r);
    model.calibration =
        readCalibration(r, model.colour.has_value(), version, &model.colourCalibration);
    r.object("fit");  // an object, written back as is
    model.fit = r.value("fit");
    if (r.has("ablation")) model.ablation = readAblation(r);
    if (version >= 4 && r.has("appearance")) {
        model.appearance = AppearanceTable::fromJson(r.value("appearance"), source);
        checkAppearanceSpansRange(*model.appearance, model.colour->range(),
                                  source + ": appearance");
    }
    if (version >= 5 && r.has("exit_offset")) {
        // Its densities are those of the gathered colour: a conditioned
        // model, drawn at any colour, has none yet (docs/exit-point.md).
        if (model.colour)
            r.fail("exit_offset",
                   "a colour-conditioned model cannot hold one (its offsets are "
                   "those of one colour)");
        model.exitOffset =
            ExitOffsetTable::fromJson(r.value("exit_offset"), source, r.pathOf("exit_offset"));
    }
    return model;
}

YarnModel loadYarnModel(const std::string& path) {
    return yarnModelFromJson(readJsonFile(path), path);
}

void saveYarnModel(const YarnModel& model, const std::string& path) {
    const json j = yarnModelToJson(model);
    // Refuse to write what the reader would reject: a non-finite weight (a
    // diverged fit) would otherwise be written as null, and a shape error
    // would only surface when the file is loaded.
    yarnModelFromJson(j, path);
    writeFileAtomic(path, formatModelJson(j));
}

}  // namespace weft
