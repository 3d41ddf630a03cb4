#include "weft/fit/yarn_model.h"

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
#include "weft/fit/yarn_lobes.h"

namespace weft {

namespace {

using nlohmann::json;

// Guards against absurd files (memory and time); far above the paper's 6-21-21-21-3.
constexpr int kMaxNetworkLayers = 16;
constexpr int kMaxNetworkWidth = 4096;
constexpr const char* kMaskingForm = "symmetric-quadratic";
constexpr const char* kCalibrationForm = "log-polynomial-sphere";

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

// The rows of a network: a layer's weight, bias and optional PReLU slopes as read.
struct LayerData {
    int in = 0, out = 0;
    std::vector<float> weight;  // row-major, out x in
    std::vector<float> bias;
    std::vector<float> prelu;  // empty: no PReLU
    bool hasPrelu = false;
};

std::vector<float> readVector(const JsonObjectReader& r, std::string_view key, int expected,
                              const std::string& why) {
    const std::vector<double> values = r.numbers(key, expected, {}, "(" + why + ")");
    std::vector<float> out(expected);
    for (int k = 0; k < expected; ++k)
        out[k] = floatNumber(values[k], r.source(), jsonIndexPath(r.pathOf(key), k));
    return out;
}

// Reads a network {"layers": [...], "output": name} of `inputs` inputs and
// `outputs` outputs under the model's key `name` ("t_net").
Mlp<float> readNetwork(const JsonObjectReader& model, const std::string& name, int inputs,
                       int outputs) {
    const JsonObjectReader network = model.object(name, {"layers", "output"});
    const json& layers = network.value("layers");
    if (!layers.is_array() || layers.empty())
        network.fail("layers", "expected a non-empty array of layers, got " + describeJson(layers));
    if (layers.size() > static_cast<size_t>(kMaxNetworkLayers))
        network.fail("layers", "a network has at most " + std::to_string(kMaxNetworkLayers) +
                                   " layers, got " + std::to_string(layers.size()));
    std::vector<JsonObjectReader> layerReaders = network.objects("layers");

    std::vector<LayerData> data;
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
        LayerData d;
        d.in = in;
        d.out = out;
        d.weight.reserve(static_cast<size_t>(in) * out);
        for (int row = 0; row < out; ++row)
            for (int col = 0; col < in; ++col)
                d.weight.push_back(floatNumber(w[row][col], layer.source(),
                                               jsonIndexPath(jsonIndexPath(weightPath, row), col)));
        const std::string outWhy = "one per row of weight";
        d.bias = readVector(layer, "bias", out, outWhy);
        d.hasPrelu = !layer.value("prelu").is_null();
        if (d.hasPrelu) d.prelu = readVector(layer, "prelu", out, outWhy + ", or null");
        data.push_back(std::move(d));
    }

    constexpr OutputFunction kOutputs[] = {OutputFunction::Sigmoid, OutputFunction::Exp,
                                           OutputFunction::Identity};
    const OutputFunction output = kOutputs[network.oneOf(
        "output", {toString(kOutputs[0]), toString(kOutputs[1]), toString(kOutputs[2])})];

    std::vector<int> widths = {inputs};
    std::vector<bool> preluFlags;
    for (const LayerData& d : data) {
        widths.push_back(d.out);
        preluFlags.push_back(d.hasPrelu);
    }
    Mlp<float> net(widths, preluFlags, output, 0);
    for (size_t l = 0; l < data.size(); ++l) {
        const int li = static_cast<int>(l);
        const LayerData& d = data[l];
        auto weight = net.weight(li);
        for (int row = 0; row < d.out; ++row)
            for (int col = 0; col < d.in; ++col)
                weight(row, col) = d.weight[static_cast<size_t>(row) * d.in + col];
        auto bias = net.bias(li);
        for (int k = 0; k < d.out; ++k) bias(k) = d.bias[k];
        auto slopes = net.preluSlopes(li);
        for (int k = 0; k < static_cast<int>(d.prelu.size()); ++k) slopes(k) = d.prelu[k];
    }
    return net;
}

json networkToJson(const Mlp<float>& net) {
    json layers = json::array();
    for (size_t l = 0; l < net.layers().size(); ++l) {
        const int li = static_cast<int>(l);
        const auto weight = net.weight(li);
        const auto bias = net.bias(li);
        const auto slopes = net.preluSlopes(li);
        // Each float written as the double of the same value: the shortest
        // decimal form of that double parses back to it, and it to the float.
        json rows = json::array();
        for (Eigen::Index row = 0; row < weight.rows(); ++row) {
            json values = json::array();
            for (Eigen::Index col = 0; col < weight.cols(); ++col)
                values.push_back(static_cast<double>(weight(row, col)));
            rows.push_back(std::move(values));
        }
        json b = json::array();
        for (Eigen::Index k = 0; k < bias.size(); ++k) b.push_back(static_cast<double>(bias(k)));
        json prelu = nullptr;
        if (net.layers()[l].prelu) {
            prelu = json::array();
            for (Eigen::Index k = 0; k < slopes.size(); ++k)
                prelu.push_back(static_cast<double>(slopes(k)));
        }
        layers.push_back({{"weight", std::move(rows)}, {"bias", std::move(b)}, {"prelu", prelu}});
    }
    return {{"layers", std::move(layers)}, {"output", toString(net.output())}};
}

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
    p.tiltDeg = r.number("tilt_deg", NumberRange::closedOpen(0, 90).with("degrees"));
    if (r.value("masking").is_null()) return p;
    const JsonObjectReader masking = r.object("masking", {"form", "coefficients"});
    masking.oneOf("form", {kMaskingForm});
    p.masking = masking.numbers("coefficients", kMaskingCoefficients);
    return p;
}

SamplingParams readSampling(const JsonObjectReader& model) {
    const JsonObjectReader r =
        model.object("sampling", {"kappa_r", "beta_m_deg", "gamma_m_deg", "kappa_m"});
    SamplingParams p;
    const NumberRange unit = NumberRange::closed(0, 1);
    p.kappaR = r.number("kappa_r", unit);
    p.betaMDeg = r.number("beta_m_deg", NumberRange::openClosed(0, 90).with("degrees"));
    p.gammaMDeg = r.number("gamma_m_deg", NumberRange::openClosed(0, 180).with("degrees"));
    p.kappaM = r.number("kappa_m", unit);
    return p;
}

// null or absent (files written before it existed): none.
EnergyCalibration readCalibration(const JsonObjectReader& model) {
    EnergyCalibration cal;
    if (!model.has("energy_calibration") || model.isNull("energy_calibration")) return cal;
    const JsonObjectReader r = model.object("energy_calibration", {"form", "degree", "r", "m"});
    r.oneOf("form", {kCalibrationForm});
    cal.degree = static_cast<int>(r.integer("degree", {0, EnergyCalibration::kMaxDegree}));
    const size_t terms = static_cast<size_t>(EnergyCalibration::termCount(cal.degree));
    for (const auto& [key, target] : {std::pair{"r", &cal.r}, std::pair{"m", &cal.m}}) {
        const std::string path = r.pathOf(key);
        const json& rows = r.value(key);
        if (!rows.is_array() || rows.size() != 3)
            r.fail(key, "expected 3 rows (R, G, B) of " + std::to_string(terms) + " numbers, got " +
                            describeJson(rows));
        for (size_t c = 0; c < 3; ++c) {
            const std::string rowPath = jsonIndexPath(path, c);
            if (!rows[c].is_array() || rows[c].size() != terms)
                throwJsonError(r.source(), rowPath,
                               "expected an array of " + std::to_string(terms) +
                                   " numbers ((degree + 1)^2), got " + describeJson(rows[c]));
            for (size_t k = 0; k < terms; ++k)
                (*target)[c].push_back(
                    readJsonNumber(rows[c][k], r.source(), jsonIndexPath(rowPath, k)));
        }
    }
    return cal;
}

// Key order of the written file: the layout order of docs/model-format.md
// (JSON objects are unordered; this is for the human reader). Keys not listed
// (the free-form "fit" block) follow in alphabetical order.
// clang-format off
constexpr std::array<std::string_view, 35> kKeyOrder = {
    "format",      "version",      "ablation", "fiber",      "ply",         "t_net",
    "m_net",       "r_lobe",       "sampling", "energy_calibration", "degree", "r", "m", "fit",
    "layers",      "output",       "weight",   "bias",       "prelu",       "tilt_deg",
    "masking",     "form",         "coefficients", "fibers", "density",     "twist",
    "c_r",         "c_tt",         "beta_r_deg", "beta_tt_deg", "gamma_tt_deg", "kappa_r",
    "beta_m_deg",  "gamma_m_deg",  "kappa_m"};
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

YarnAblation readAblation(const JsonObjectReader& model) {
    constexpr YarnAblation kAblations[] = {YarnAblation::Naive, YarnAblation::NoRLobe};
    return kAblations[model.oneOf(
        "ablation", {yarnAblationName(kAblations[0]), yarnAblationName(kAblations[1])})];
}

}  // namespace

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
    if (!model.calibration.empty())
        calibration = {{"form", kCalibrationForm},
                       {"degree", model.calibration.degree},
                       {"r", model.calibration.r},
                       {"m", model.calibration.m}};
    json document = {{"format", kYarnModelFormat},
                     {"version", kYarnModelVersion},
                     {"fiber", model.fiber.toJson()},
                     {"ply",
                      {{"fibers", model.ply.fibers},
                       {"density", model.ply.density},
                       {"twist", model.ply.twist}}},
                     {"t_net", networkToJson(model.tNet)},
                     {"m_net", networkToJson(model.mNet)},
                     {"r_lobe", {{"tilt_deg", model.rLobe.tiltDeg}, {"masking", masking}}},
                     {"sampling",
                      {{"kappa_r", model.sampling.kappaR},
                       {"beta_m_deg", model.sampling.betaMDeg},
                       {"gamma_m_deg", model.sampling.gammaMDeg},
                       {"kappa_m", model.sampling.kappaM}}},
                     {"energy_calibration", calibration},
                     {"fit", model.fit}};
    // Absent for the full model, so that its files stay as they were.
    if (model.ablation != YarnAblation::None)
        document["ablation"] = yarnAblationName(model.ablation);
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
    if (r.integer("version") != kYarnModelVersion)
        r.fail("version", "unsupported version " + describeJson(r.value("version")) +
                              " (supported: " + std::to_string(kYarnModelVersion) + ")");
    // energy_calibration may be absent (files written before it existed);
    // ablation is absent for the full model.
    r.allowKeys({"format", "version", "ablation", "fiber", "ply", "t_net", "m_net", "r_lobe",
                 "sampling", "energy_calibration", "fit"});

    YarnModel model;
    model.fiber = FiberParams::fromJson(r.value("fiber"), source, "fiber");
    model.ply = readPly(r);
    model.tNet = readNetwork(r, "t_net", 3, 1);
    model.mNet = readNetwork(r, "m_net", 6, 3);
    model.rLobe = readRLobe(r);
    model.sampling = readSampling(r);
    model.calibration = readCalibration(r);
    r.object("fit");  // an object, written back as is
    model.fit = r.value("fit");
    if (r.has("ablation")) model.ablation = readAblation(r);
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
    std::string text;
    writeValue(j, 0, true, text);
    writeFileAtomic(path, text + "\n");
}

}  // namespace weft
