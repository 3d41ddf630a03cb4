// weft fit's configuration (fit_config.h): strict JSON reading and writing.
#include "weft/fit/fit_config.h"

#include "weft/core/error.h"
#include "weft/core/json_file.h"
#include "weft/core/json_reader.h"
#include "weft/yarn/energy_calibration.h"
#include "weft/yarn/network_capacity.h"

namespace weft {

namespace {

const char* lossName(Loss loss) { return loss == Loss::Mse ? "mse" : "log-mse"; }

nlohmann::json trainingToJson(const NetworkTraining& t) {
    return {{"hidden", t.hidden},          {"steps", t.steps}, {"restarts", t.restarts},
            {"batch", t.batch},            {"learning_rate", t.learningRate},
            {"final_learning_rate", t.finalLearningRate}, {"loss", lossName(t.loss)}};
}

NetworkTraining trainingFromJson(JsonObjectReader r, NetworkTraining t) {
    r.allowKeys(
        {"hidden", "steps", "restarts", "batch", "learning_rate", "final_learning_rate", "loss"});
    if (r.has("hidden")) {
        // Any list of positive widths here; FitConfig::validate holds them to
        // what the renderer runs, with the reason in its message.
        t.hidden.clear();
        for (int64_t w : r.integers("hidden", 1, 64, {1, 4096}, "(layer widths)"))
            t.hidden.push_back(static_cast<int>(w));
    }
    if (r.has("steps")) t.steps = r.integer("steps", {1, 100'000'000});
    if (r.has("restarts")) t.restarts = static_cast<int>(r.integer("restarts", {1, 64}));
    if (r.has("batch")) t.batch = static_cast<int>(r.integer("batch", {8, 1 << 20}));
    const NumberRange rate = NumberRange::openClosed(0, 1);
    if (r.has("learning_rate")) t.learningRate = r.number("learning_rate", rate);
    if (r.has("final_learning_rate")) t.finalLearningRate = r.number("final_learning_rate", rate);
    if (r.has("loss")) t.loss = r.oneOf("loss", {"mse", "log-mse"}) == 0 ? Loss::Mse : Loss::LogMse;
    return t;
}

}  // namespace

FitConfig FitConfig::fromJson(const nlohmann::json& j, const std::string& source) {
    JsonObjectReader r(j, source);
    r.allowKeys({"t_net", "m_net", "jitter", "masking", "threads", "energy_calibration_degree",
                 "appearance_nodes", "exit_offset"});
    FitConfig c;
    if (r.has("t_net")) c.t = trainingFromJson(r.object("t_net"), c.t);
    if (r.has("m_net")) c.m = trainingFromJson(r.object("m_net"), c.m);
    if (r.has("jitter")) c.jitter = r.boolean("jitter");
    if (r.has("masking")) c.masking = r.boolean("masking");
    if (r.has("energy_calibration_degree"))
        c.calibrationDegree = static_cast<int>(r.integer(
            "energy_calibration_degree", {-1, EnergyCalibration::kMaxDegree, "(-1: off)"}));
    if (r.has("appearance_nodes"))
        c.appearanceNodes =
            static_cast<int>(r.integer("appearance_nodes", {2, AppearanceTable::kMaxNodes}));
    if (r.has("exit_offset")) c.exitOffset = r.boolean("exit_offset");
    if (r.has("threads"))
        c.threads = static_cast<int>(r.integer("threads", {0, 1024, "(0: all cores)"}));
    c.validate(source);
    return c;
}

void FitConfig::validate(const std::string& source) const {
    checkHiddenWidths(t.hidden, kTransmissionCapacity, source + ": t_net.hidden");
    checkHiddenWidths(m.hidden, kScatteringCapacity, source + ": m_net.hidden");
    checkRange(source + ": energy_calibration_degree =", calibrationDegree, -1,
               EnergyCalibration::kMaxDegree, " (-1: off)");
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
            {"appearance_nodes", appearanceNodes},
            {"exit_offset", exitOffset},
            {"threads", threads}};
}

}  // namespace weft
