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
#include "weft/yarn/yarn_lobes.h"

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


// Validating reader state: every error names the source, then the JSON path.
class Reader {
  public:
    explicit Reader(const std::string& source) : source_(source) {}

    [[noreturn]] void fail(const std::string& path, const std::string& message) const {
        throw InputError(source_ + ": " + (path.empty() ? "" : path + ": ") + message);
    }

    const std::string& source() const { return source_; }

    // An object whose keys are exactly `keys`: unknown keys and missing keys are errors.
    void expectKeys(const json& j, const std::string& path,
                    std::initializer_list<const char*> keys) const {
        if (!j.is_object()) fail(path, "expected an object, got " + describeJson(j));
        std::string allowed;
        for (const char* k : keys) allowed += (allowed.empty() ? "" : ", ") + std::string(k);
        for (const auto& item : j.items()) {
            bool known = false;
            for (const char* k : keys) known = known || item.key() == k;
            if (!known) fail(path, "unknown key \"" + item.key() + "\" (allowed: " + allowed + ")");
        }
        for (const char* k : keys)
            if (!j.contains(k)) fail(path, "missing key \"" + std::string(k) + "\"");
    }

    // A finite number (any JSON number type).
    double number(const json& v, const std::string& path) const {
        if (!v.is_number()) fail(path, "expected a number, got " + describeJson(v));
        const double x = v.get<double>();
        if (!std::isfinite(x)) fail(path, "expected a finite number, got " + formatNumber(x));
        return x;
    }

    // A finite number that is also a finite float (network parameters are float32).
    float floatNumber(const json& v, const std::string& path) const {
        const double x = number(v, path);
        if (std::fabs(x) > std::numeric_limits<float>::max())
            fail(path,
                 "expected a finite 32-bit float, got " + formatNumber(x) + " (beyond +-3.4e38)");
        return static_cast<float>(x);
    }

    double numberIn(const json& v, const std::string& path, bool ok(double),
                    const char* range) const {
        const double x = number(v, path);
        if (!ok(x)) fail(path, formatNumber(x) + " is out of range: allowed " + range);
        return x;
    }

  private:
    const std::string& source_;
};

std::vector<float> readVector(const Reader& r, const json& v, const std::string& path, int expected,
                              const std::string& why) {
    if (!v.is_array() || v.size() != static_cast<size_t>(expected))
        r.fail(path, "expected " + std::to_string(expected) + " numbers (" + why + "), got " +
                         describeJson(v));
    std::vector<float> out(expected);
    for (int k = 0; k < expected; ++k) out[k] = r.floatNumber(v[k], jsonIndexPath(path, k));
    return out;
}

// Reads a network {"layers": [...], "output": name} of `inputs` inputs and
// `outputs` outputs; `name` is its key ("t_net").
NetworkWeights readNetwork(const Reader& r, const json& j, const std::string& name, int inputs,
                           int outputs) {
    r.expectKeys(j, name, {"layers", "output"});
    const std::string layersPath = jsonChildPath(name, "layers");
    const json& layers = j.at("layers");
    if (!layers.is_array() || layers.empty())
        r.fail(layersPath, "expected a non-empty array of layers, got " + describeJson(layers));
    if (layers.size() > static_cast<size_t>(kMaxNetworkLayers))
        r.fail(layersPath, "a network has at most " + std::to_string(kMaxNetworkLayers) +
                               " layers, got " + std::to_string(layers.size()));

    NetworkWeights net;
    std::vector<NetworkLayer>& data = net.layers;
    for (size_t l = 0; l < layers.size(); ++l) {
        const std::string path = jsonIndexPath(layersPath, l);
        const json& layer = layers[l];
        r.expectKeys(layer, path, {"weight", "bias", "prelu"});
        const bool last = l + 1 == layers.size();
        // Shape: columns chain from the previous layer (or the network inputs);
        // the last layer's rows are the network outputs, a hidden layer's rows its width.
        const int in = l == 0 ? inputs : data.back().out;
        const std::string inWhy =
            l == 0 ? name + " has " + plural(inputs, "input")
                   : "layers[" + std::to_string(l - 1) + "] has " + plural(in, "output");
        const std::string weightPath = jsonChildPath(path, "weight");
        const json& w = layer.at("weight");
        if (!w.is_array() || w.empty())
            r.fail(weightPath, "expected a non-empty array of rows, got " + describeJson(w));
        if (w.size() > static_cast<size_t>(kMaxNetworkWidth))
            r.fail(weightPath, "a layer has at most " + std::to_string(kMaxNetworkWidth) +
                                   " outputs, got " + std::to_string(w.size()) + " rows");
        const int out = last ? outputs : static_cast<int>(w.size());
        const std::string shape =
            "expected " + std::to_string(out) + " rows of " + std::to_string(in) + " numbers";
        if (last && w.size() != static_cast<size_t>(outputs))
            r.fail(weightPath, shape + " (" + name + " has " + plural(outputs, "output") +
                                   "), got " + plural(static_cast<int>(w.size()), "row"));
        for (size_t row = 0; row < w.size(); ++row)
            if (!w[row].is_array() || w[row].size() != static_cast<size_t>(in))
                r.fail(weightPath, shape + " (" + inWhy + "), got row " + std::to_string(row) +
                                       " = " + describeJson(w[row]));
        NetworkLayer d;
        d.in = in;
        d.out = out;
        d.weight.reserve(static_cast<size_t>(in) * out);
        for (int row = 0; row < out; ++row)
            for (int col = 0; col < in; ++col)
                d.weight.push_back(
                    r.floatNumber(w[row][col], jsonIndexPath(jsonIndexPath(weightPath, row), col)));
        const std::string outWhy = "one per row of weight";
        d.bias = readVector(r, layer.at("bias"), jsonChildPath(path, "bias"), out, outWhy);
        const json& prelu = layer.at("prelu");
        if (!prelu.is_null())
            d.prelu = readVector(r, prelu, jsonChildPath(path, "prelu"), out, outWhy + ", or null");
        data.push_back(std::move(d));
    }

    const json& outputName = j.at("output");
    const std::string outputPath = jsonChildPath(name, "output");
    if (!outputName.is_string())
        r.fail(outputPath,
               "expected a string (sigmoid, exp or identity), got " + describeJson(outputName));
    try {
        net.output = outputFunctionFromString(outputName.get<std::string>());
    } catch (const InputError& e) {
        r.fail(outputPath, e.what());
    }
    return net;
}

json networkToJson(const NetworkWeights& net) {
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

PlyParams readPly(const Reader& r, const json& j) {
    r.expectKeys(j, "ply", {"fibers", "density", "twist"});
    PlyParams ply;
    const json& fibers = j.at("fibers");
    if (!fibers.is_number_integer())
        r.fail("ply.fibers", "expected an integer, got " + describeJson(fibers));
    const int64_t n =
        fibers.is_number_unsigned()
            ? static_cast<int64_t>(std::min<uint64_t>(fibers.get<uint64_t>(), uint64_t{1} << 62))
            : fibers.get<int64_t>();
    if (n < 1 || n > kMaxPlyFibers)
        r.fail("ply.fibers", std::to_string(n) + " is out of range: allowed [1, " +
                                 std::to_string(kMaxPlyFibers) + "]");
    ply.fibers = static_cast<int>(n);
    ply.density = r.number(j.at("density"), "ply.density");
    ply.twist = r.number(j.at("twist"), "ply.twist");
    try {
        ply.validate();  // its messages start with "ply: "
    } catch (const InputError& e) {
        throw InputError(r.source() + ": " + e.what());
    }
    return ply;
}

RLobeParams readRLobe(const Reader& r, const json& j) {
    r.expectKeys(j, "r_lobe", {"tilt_deg", "masking"});
    RLobeParams p;
    p.tiltDeg = r.numberIn(
        j.at("tilt_deg"), "r_lobe.tilt_deg", [](double x) { return x >= 0 && x < 90; },
        "[0, 90) degrees");
    const json& masking = j.at("masking");
    if (masking.is_null()) return p;
    r.expectKeys(masking, "r_lobe.masking", {"form", "coefficients"});
    const json& form = masking.at("form");
    if (!form.is_string() || form.get<std::string>() != kMaskingForm)
        r.fail("r_lobe.masking.form",
               std::string("expected \"") + kMaskingForm + "\", got " + describeJson(form));
    const json& c = masking.at("coefficients");
    const std::string path = "r_lobe.masking.coefficients";
    if (!c.is_array() || c.size() != static_cast<size_t>(kMaskingCoefficients))
        r.fail(path,
               "expected " + std::to_string(kMaskingCoefficients) + " numbers, got " + describeJson(c));
    for (size_t k = 0; k < c.size(); ++k) p.masking.push_back(r.number(c[k], jsonIndexPath(path, k)));
    return p;
}

SamplingParams readSampling(const Reader& r, const json& j) {
    r.expectKeys(j, "sampling", {"kappa_r", "beta_m_deg", "gamma_m_deg", "kappa_m"});
    SamplingParams p;
    const auto unit = [](double x) { return x >= 0 && x <= 1; };
    p.kappaR = r.numberIn(j.at("kappa_r"), "sampling.kappa_r", unit, "[0, 1]");
    p.betaMDeg = r.numberIn(
        j.at("beta_m_deg"), "sampling.beta_m_deg", [](double x) { return x > 0 && x <= 90; },
        "(0, 90] degrees");
    p.gammaMDeg = r.numberIn(
        j.at("gamma_m_deg"), "sampling.gamma_m_deg", [](double x) { return x > 0 && x <= 180; },
        "(0, 180] degrees");
    p.kappaM = r.numberIn(j.at("kappa_m"), "sampling.kappa_m", unit, "[0, 1]");
    return p;
}

EnergyCalibration readCalibration(const Reader& r, const json& j) {
    EnergyCalibration cal;
    if (j.is_null()) return cal;
    r.expectKeys(j, "energy_calibration", {"form", "degree", "r", "m"});
    const json& form = j.at("form");
    if (!form.is_string() || form.get<std::string>() != kCalibrationForm)
        r.fail("energy_calibration.form",
               std::string("expected \"") + kCalibrationForm + "\", got " + describeJson(form));
    const json& degree = j.at("degree");
    if (!degree.is_number_integer() || degree.get<int64_t>() < 0 ||
        degree.get<int64_t>() > EnergyCalibration::kMaxDegree)
        r.fail("energy_calibration.degree",
               "expected an integer in [0, " + std::to_string(EnergyCalibration::kMaxDegree) +
                   "], got " + describeJson(degree));
    cal.degree = degree.get<int>();
    const size_t terms = static_cast<size_t>(EnergyCalibration::termCount(cal.degree));
    for (const auto& [key, target] : {std::pair{"r", &cal.r}, std::pair{"m", &cal.m}}) {
        const std::string path = std::string("energy_calibration.") + key;
        const json& rows = j.at(key);
        if (!rows.is_array() || rows.size() != 3)
            r.fail(path, "expected 3 rows (R, G, B) of " + std::to_string(terms) +
                             " numbers, got " + describeJson(rows));
        for (size_t c = 0; c < 3; ++c) {
            const std::string rowPath = jsonIndexPath(path, c);
            if (!rows[c].is_array() || rows[c].size() != terms)
                r.fail(rowPath, "expected " + std::to_string(terms) + " numbers ((degree + 1)^2), got " +
                                    describeJson(rows[c]));
            for (size_t k = 0; k < terms; ++k)
                (*target)[c].push_back(r.number(rows[c][k], jsonIndexPath(rowPath, k)));
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

YarnAblation readAblation(const Reader& r, const json& j) {
    const std::string allowed = "(allowed: \"naive\", \"no_r_lobe\"; absent for the full model)";
    if (!j.is_string())
        r.fail("ablation", "expected a string " + allowed + ", got " + describeJson(j));
    for (YarnAblation a : {YarnAblation::Naive, YarnAblation::NoRLobe})
        if (j.get<std::string>() == yarnAblationName(a)) return a;
    r.fail("ablation", "unknown value " + describeJson(j) + " " + allowed);
}

}  // namespace

namespace {

void checkRange(double v, bool ok, const std::string& key, const char* range) {
    if (!ok || !std::isfinite(v))
        throw InputError(key + " = " + formatNumber(v) + " is out of range: allowed " + range);
}

}  // namespace

void RLobeParams::validate() const {
    checkRange(tiltDeg, tiltDeg >= 0 && tiltDeg < 90, "r_lobe.tilt_deg", "[0, 90) degrees");
    if (!masking.empty() && masking.size() != kMaskingCoefficients)
        throw InputError("r_lobe.masking: expected " + std::to_string(kMaskingCoefficients) +
                         " coefficients, got " + std::to_string(masking.size()));
    for (size_t k = 0; k < masking.size(); ++k)
        checkRange(masking[k], true, "r_lobe.masking.coefficients[" + std::to_string(k) + "]",
                   "finite numbers");
}

void SamplingParams::validate() const {
    checkRange(kappaR, kappaR >= 0 && kappaR <= 1, "sampling.kappa_r", "[0, 1]");
    checkRange(betaMDeg, betaMDeg > 0 && betaMDeg <= 90, "sampling.beta_m_deg", "(0, 90] degrees");
    checkRange(gammaMDeg, gammaMDeg > 0 && gammaMDeg <= 180, "sampling.gamma_m_deg",
               "(0, 180] degrees");
    checkRange(kappaM, kappaM >= 0 && kappaM <= 1, "sampling.kappa_m", "[0, 1]");
}

void YarnModel::validate() const {
    tNet.validate("t_net", 3, 1, OutputFunction::Sigmoid, "P(T|wi) must lie in [0, 1]");
    mNet.validate("m_net", 6, 3, OutputFunction::Exp, "S_M must be non-negative");
    rLobe.validate();
    sampling.validate();
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
    const Reader r(source);
    if (!j.is_object())
        r.fail("", std::string("expected a JSON object (a ") + kYarnModelFormat + " file), got " +
                       describeJson(j));
    // Format and version first: a file of another kind or version gets that
    // message rather than a list of unknown keys.
    if (!j.contains("format"))
        r.fail("", std::string("missing key \"format\" (expected \"") + kYarnModelFormat +
                       "\": not a weft yarn model?)");
    const json& format = j.at("format");
    if (!format.is_string() || format.get<std::string>() != kYarnModelFormat)
        r.fail("format",
               std::string("expected \"") + kYarnModelFormat + "\", got " + describeJson(format));
    if (!j.contains("version")) r.fail("", "missing key \"version\"");
    const json& version = j.at("version");
    if (!version.is_number_integer())
        r.fail("version", "expected an integer, got " + describeJson(version));
    if (version.get<int64_t>() != kYarnModelVersion)
        r.fail("version", "unsupported version " + describeJson(version) +
                              " (supported: " + std::to_string(kYarnModelVersion) + ")");
    // energy_calibration may be absent (files written before it existed): null;
    // ablation is absent for the full model.
    json keys = json::object();
    for (const auto& item : j.items()) keys[item.key()] = nullptr;
    keys["energy_calibration"] = nullptr;
    keys["ablation"] = nullptr;
    r.expectKeys(keys, "",
                 {"format", "version", "ablation", "fiber", "ply", "t_net", "m_net", "r_lobe",
                  "sampling", "energy_calibration", "fit"});

    YarnModel model;
    model.fiber = FiberParams::fromJson(j.at("fiber"), source + ": fiber");
    model.ply = readPly(r, j.at("ply"));
    model.tNet = readNetwork(r, j.at("t_net"), "t_net", 3, 1);
    model.mNet = readNetwork(r, j.at("m_net"), "m_net", 6, 3);
    model.rLobe = readRLobe(r, j.at("r_lobe"));
    model.sampling = readSampling(r, j.at("sampling"));
    if (j.contains("energy_calibration"))
        model.calibration = readCalibration(r, j.at("energy_calibration"));
    const json& fit = j.at("fit");
    if (!fit.is_object()) r.fail("fit", "expected an object, got " + describeJson(fit));
    model.fit = fit;
    if (j.contains("ablation")) model.ablation = readAblation(r, j.at("ablation"));
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
