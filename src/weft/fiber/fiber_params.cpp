#include "weft/fiber/fiber_params.h"

#include <cmath>
#include <nlohmann/json.hpp>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/json_file.h"
#include "weft/core/json_message.h"
#include "weft/core/json_reader.h"

namespace weft {

namespace {

// The allowed values, shared by validate() and the JSON reader.
const NumberRange kAttenuationRange = NumberRange::closed(0, 1);
const NumberRange kAngleRange = NumberRange::openClosed(0, 90).with("degrees");

void checkAngle(double deg, const char* field, const std::string& source) {
    if (!std::isfinite(deg) || !kAngleRange.contains(deg))
        throwJsonOutOfRange(source, field, formatNumber(deg), kAngleRange.text());
}

void checkAttenuation(const Rgb& c, const char* field, const std::string& source) {
    for (int i = 0; i < 3; ++i)
        if (!std::isfinite(c[i]) || !kAttenuationRange.contains(c[i]))
            throwJsonOutOfRange(source, std::string(field) + "[" + std::to_string(i) + "]",
                                formatNumber(c[i]), kAttenuationRange.text());
}

// [r, g, b], or one number for all three.
Rgb readRgb(const JsonObjectReader& r, const char* key) {
    if (r.value(key).is_number()) return Rgb(r.number(key, kAttenuationRange));
    const std::vector<double> c =
        r.numbers(key, 3, kAttenuationRange, "(r, g, b; or one number for all three)");
    return {c[0], c[1], c[2]};
}

}  // namespace

void FiberParams::validate(const std::string& source) const {
    checkAttenuation(cR, "c_r", source);
    checkAttenuation(cTT, "c_tt", source);
    checkAngle(betaRDeg, "beta_r_deg", source);
    checkAngle(betaTTDeg, "beta_tt_deg", source);
    checkAngle(gammaTTDeg, "gamma_tt_deg", source);
}

FiberParams FiberParams::fromJson(const nlohmann::json& j, const std::string& source,
                                  const std::string& path) {
    JsonObjectReader r(j, source, path);
    r.allowKeys({"c_r", "c_tt", "beta_r_deg", "beta_tt_deg", "gamma_tt_deg"});
    FiberParams p;
    p.cR = readRgb(r, "c_r");
    p.cTT = readRgb(r, "c_tt");
    p.betaRDeg = r.number("beta_r_deg", kAngleRange);
    p.betaTTDeg = r.number("beta_tt_deg", kAngleRange);
    p.gammaTTDeg = r.number("gamma_tt_deg", kAngleRange);
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
