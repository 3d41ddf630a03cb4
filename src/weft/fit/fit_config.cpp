// weft fit's configuration (fit_config.h): strict JSON reading and writing.
#include "weft/fit/fit_config.h"

#include <set>
#include <utility>

#include "weft/core/error.h"
#include "weft/core/json_file.h"
#include "weft/yarn/energy_calibration.h"

namespace weft {

namespace {

const char* lossName(Loss loss) { return loss == Loss::Mse ? "mse" : "log-mse"; }

Loss lossFromString(const std::string& name, const std::string& where) {
    if (name == "mse") return Loss::Mse;
    if (name == "log-mse") return Loss::LogMse;
    throw InputError(where + ": unknown loss \"" + name + "\" (allowed: mse, log-mse)");
}

nlohmann::json trainingToJson(const NetworkTraining& t) {
    return {{"hidden", t.hidden},          {"steps", t.steps}, {"restarts", t.restarts},
            {"batch", t.batch},            {"learning_rate", t.learningRate},
            {"final_learning_rate", t.finalLearningRate}, {"loss", lossName(t.loss)}};
}

template <typename T>
T numberAt(const nlohmann::json& j, const std::string& where) {
    if (!j.is_number()) throw InputError(where + ": expected a number");
    if constexpr (std::is_integral_v<T>) {
        if (!j.is_number_integer()) throw InputError(where + ": expected an integer");
    }
    return j.get<T>();
}

NetworkTraining trainingFromJson(const nlohmann::json& j, NetworkTraining t, const std::string& where) {
    if (!j.is_object()) throw InputError(where + ": expected an object");
    static const std::set<std::string> known = {"hidden", "steps", "restarts", "batch",
                                                "learning_rate", "final_learning_rate", "loss"};
    for (const auto& [key, value] : j.items())
        if (!known.count(key)) throw InputError(where + ": unknown key \"" + key + "\"");
    if (j.contains("hidden")) {
        const auto& h = j["hidden"];
        if (!h.is_array() || h.empty() || h.size() > 8)
            throw InputError(where + ".hidden: expected 1 to 8 layer widths");
        t.hidden.clear();
        for (size_t k = 0; k < h.size(); ++k) {
            const int w = numberAt<int>(h[k], where + ".hidden[" + std::to_string(k) + "]");
            if (w < 1 || w > 256)
                throw InputError(where + ".hidden[" + std::to_string(k) + "] = " + std::to_string(w) +
                                 " is out of range: allowed [1, 256]");
            t.hidden.push_back(w);
        }
    }
    if (j.contains("steps")) t.steps = numberAt<int64_t>(j["steps"], where + ".steps");
    if (j.contains("restarts")) t.restarts = numberAt<int>(j["restarts"], where + ".restarts");
    if (j.contains("batch")) t.batch = numberAt<int>(j["batch"], where + ".batch");
    if (j.contains("learning_rate"))
        t.learningRate = numberAt<double>(j["learning_rate"], where + ".learning_rate");
    if (j.contains("final_learning_rate"))
        t.finalLearningRate = numberAt<double>(j["final_learning_rate"], where + ".final_learning_rate");
    if (j.contains("loss")) {
        if (!j["loss"].is_string()) throw InputError(where + ".loss: expected a string");
        t.loss = lossFromString(j["loss"].get<std::string>(), where + ".loss");
    }
    if (t.steps < 1 || t.steps > 100'000'000)
        throw InputError(where + ".steps = " + std::to_string(t.steps) + " is out of range: allowed [1, 1e8]");
    if (t.restarts < 1 || t.restarts > 64)
        throw InputError(where + ".restarts = " + std::to_string(t.restarts) + " is out of range: allowed [1, 64]");
    if (t.batch < 8 || t.batch > 1 << 20)
        throw InputError(where + ".batch = " + std::to_string(t.batch) + " is out of range: allowed [8, 1048576]");
    for (auto [value, name] : {std::pair{t.learningRate, "learning_rate"},
                               std::pair{t.finalLearningRate, "final_learning_rate"}})
        if (!(value > 0 && value <= 1))
            throw InputError(where + "." + name + " = " + std::to_string(value) +
                             " is out of range: allowed (0, 1]");
    return t;
}

}  // namespace

FitConfig FitConfig::fromJson(const nlohmann::json& j, const std::string& source) {
    if (!j.is_object()) throw InputError(source + ": the fit configuration must be a JSON object");
    static const std::set<std::string> known = {"t_net",   "m_net",   "jitter",
                                                "masking", "threads", "energy_calibration_degree"};
    for (const auto& [key, value] : j.items())
        if (!known.count(key))
            throw InputError(source + ": unknown key \"" + key +
                             "\" (allowed: t_net, m_net, jitter, masking, threads, "
                             "energy_calibration_degree)");
    FitConfig c;
    if (j.contains("t_net")) c.t = trainingFromJson(j["t_net"], c.t, source + ": t_net");
    if (j.contains("m_net")) c.m = trainingFromJson(j["m_net"], c.m, source + ": m_net");
    for (auto [flag, name] : {std::pair{&c.jitter, "jitter"}, std::pair{&c.masking, "masking"}}) {
        if (!j.contains(name)) continue;
        if (!j[name].is_boolean()) throw InputError(source + ": " + name + ": expected true or false");
        *flag = j[name].get<bool>();
    }
    if (j.contains("energy_calibration_degree")) {
        c.calibrationDegree =
            numberAt<int>(j["energy_calibration_degree"], source + ": energy_calibration_degree");
        if (c.calibrationDegree < -1 || c.calibrationDegree > EnergyCalibration::kMaxDegree)
            throw InputError(source + ": energy_calibration_degree = " +
                             std::to_string(c.calibrationDegree) + " is out of range: allowed [-1, " +
                             std::to_string(EnergyCalibration::kMaxDegree) + "] (-1: off)");
    }
    if (j.contains("threads")) {
        c.threads = numberAt<int>(j["threads"], source + ": threads");
        if (c.threads < 0 || c.threads > 1024)
            throw InputError(source + ": threads = " + std::to_string(c.threads) +
                             " is out of range: allowed [0, 1024] (0: all cores)");
    }
    return c;
}

FitConfig FitConfig::fromJsonFile(const std::string& path) {
    return fromJson(readJsonFile(path), path);
}

nlohmann::json FitConfig::toJson() const {
    return {{"t_net", trainingToJson(t)},
            {"m_net", trainingToJson(m)},
            {"jitter", jitter},
            {"masking", masking},
            {"energy_calibration_degree", calibrationDegree},
            {"threads", threads}};
}
}  // namespace weft
