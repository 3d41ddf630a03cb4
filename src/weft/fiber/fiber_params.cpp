#include "weft/fiber/fiber_params.h"

#include <cmath>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/json_file.h"

namespace weft {

namespace {

void checkAngle(double deg, const char* field, const std::string& source) {
    if (!std::isfinite(deg) || !(deg > 0.0) || !(deg <= 90.0)) {
        std::ostringstream msg;
        msg << source << ": " << field << " = " << deg
            << " is out of range: allowed (0, 90] degrees";
        throw InputError(msg.str());
    }
}

void checkAttenuation(const Rgb& c, const char* field, const std::string& source) {
    for (int i = 0; i < 3; ++i) {
        if (!std::isfinite(c[i]) || c[i] < 0.0 || c[i] > 1.0) {
            std::ostringstream msg;
            msg << source << ": " << field << "[" << i << "] = " << c[i]
                << " is out of range: allowed [0, 1]";
            throw InputError(msg.str());
        }
    }
}

double readNumber(const nlohmann::json& j, const char* field, const std::string& source) {
    if (!j.contains(field)) throw InputError(source + ": missing field \"" + field + "\"");
    const auto& v = j.at(field);
    if (!v.is_number())
        throw InputError(source + ": field \"" + field + "\" must be a number, got " + v.dump());
    return v.get<double>();
}

Rgb readRgb(const nlohmann::json& j, const char* field, const std::string& source) {
    if (!j.contains(field)) throw InputError(source + ": missing field \"" + field + "\"");
    const auto& v = j.at(field);
    if (v.is_number()) return Rgb(v.get<double>());
    if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() ||
        !v[2].is_number())
        throw InputError(source + ": field \"" + field +
                         "\" must be an array of 3 numbers [r, g, b], got " + v.dump());
    return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
}

}  // namespace

void FiberParams::validate(const std::string& source) const {
    checkAttenuation(cR, "c_r", source);
    checkAttenuation(cTT, "c_tt", source);
    checkAngle(betaRDeg, "beta_r_deg", source);
    checkAngle(betaTTDeg, "beta_tt_deg", source);
    checkAngle(gammaTTDeg, "gamma_tt_deg", source);
}

FiberParams FiberParams::fromJson(const nlohmann::json& j, const std::string& source) {
    if (!j.is_object()) throw InputError(source + ": fiber parameters must be a JSON object");
    static const std::set<std::string> known = {"c_r", "c_tt", "beta_r_deg", "beta_tt_deg",
                                                "gamma_tt_deg"};
    for (const auto& item : j.items()) {
        if (!known.count(item.key()))
            throw InputError(source + ": unknown field \"" + item.key() +
                             "\" (allowed: c_r, c_tt, beta_r_deg, beta_tt_deg, gamma_tt_deg)");
    }
    FiberParams p;
    p.cR = readRgb(j, "c_r", source);
    p.cTT = readRgb(j, "c_tt", source);
    p.betaRDeg = readNumber(j, "beta_r_deg", source);
    p.betaTTDeg = readNumber(j, "beta_tt_deg", source);
    p.gammaTTDeg = readNumber(j, "gamma_tt_deg", source);
    p.validate(source);
    return p;
}

FiberParams FiberParams::fromJsonFile(const std::string& path) {
    return fromJson(readJsonFile(path), path);
}

nlohmann::json FiberParams::toJson() const {
    return {{"c_r", {cR.r, cR.g, cR.b}},
            {"c_tt", {cTT.r, cTT.g, cTT.b}},
            {"beta_r_deg", betaRDeg},
            {"beta_tt_deg", betaTTDeg},
            {"gamma_tt_deg", gammaTTDeg}};
}

const std::vector<MaterialPreset>& materialPresets() {
    // Paper Table 3 (DESIGN.md 3): N, rho, alpha; C_R; C_TT; beta_R, beta_TT, gamma_TT.
    static const std::vector<MaterialPreset> presets = {
        {"fleece",
         {{0.040, 0.087, 0.087}, {0.452, 0.725, 0.948}, 7.238, 10.000, 25.989},
         {300, 0.30, 0.24}},
        {"silk",
         {{0.745, 0.008, 0.070}, {0.620, 0.553, 0.562}, 1.000, 10.000, 19.823},
         {300, 0.20, 0.00}},
        {"polyester",
         {{0.700, 0.700, 0.700}, {0.600, 0.000, 0.800}, 5.238, 20.000, 25.000},
         {200, 0.40, 0.20}},
        {"cotton",
         {{0.989, 0.959, 0.874}, {0.999, 0.999, 0.999}, 1.000, 27.197, 38.269},
         {600, 0.35, 0.06}},
        {"gabardine",
         {{0.185, 0.047, 0.069}, {0.999, 0.330, 0.354}, 2.141, 10.000, 23.548},
         {450, 0.25, 0.12}},
    };
    return presets;
}

const MaterialPreset& findMaterialPreset(std::string_view name) {
    std::string names;
    for (const auto& preset : materialPresets()) {
        if (preset.name == name) return preset;
        names += (names.empty() ? "" : ", ") + std::string(preset.name);
    }
    throw InputError("unknown preset \"" + std::string(name) + "\" (allowed: " + names + ")");
}

}  // namespace weft
