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
// Narrower lobes than 0.1 degrees are far below what fibers show, and at the
// extreme (1e-300 degrees) eval underflows to 0 everywhere: a silently black fiber.
const NumberRange kAngleRange = NumberRange::closed(0.1, 90).with("degrees");

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

}  // namespace weft
