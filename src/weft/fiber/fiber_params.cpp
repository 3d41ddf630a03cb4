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

}  // namespace weft
