#include <algorithm>
#include <cmath>
#include <sstream>

#include "commands.h"
#include "weft/core/error.h"
#include "weft/core/npy.h"
#include "weft/yarn/material_preset.h"

namespace weft::cmd {

void MaterialOptions::add(CLI::App& app, bool withPly) {
    std::string names;
    for (const auto& p : materialPresets()) names += (names.empty() ? "" : ", ") + std::string(p.name);
    app.add_option("--preset", preset,
                   std::string("material of the paper's Table 3: ") + names +
                       (withPly ? " (fiber and ply parameters)" : ""));
    app.add_option("--params", paramsFile,
                   "fiber parameters as JSON: {\"c_r\":[r,g,b],\"c_tt\":[r,g,b],"
                   "\"beta_r_deg\":x,\"beta_tt_deg\":x,\"gamma_tt_deg\":x}");
}

FiberParams MaterialOptions::fiber() const {
    if (preset.empty() == paramsFile.empty())
        throw InputError("give exactly one of --preset NAME or --params FILE");
    if (!preset.empty()) return findMaterialPreset(preset).fiber;
    return FiberParams::fromJsonFile(paramsFile);
}

void PlyGeometryOptions::add(CLI::App& app) {
    fibersOpt = app.add_option("--fibers", fibers, "fiber count N >= 1");
    densityOpt = app.add_option("--density", density, "fiber density rho in (0, 1)");
    twistOpt = app.add_option("--twist", twist, "twist factor alpha >= 0");
}

Vec3 parseVec3(const std::string& text, const std::string& flag) {
    std::istringstream in(text);
    double v[3];
    char comma;
    bool ok = static_cast<bool>(in >> v[0] >> comma) && comma == ',' &&
              static_cast<bool>(in >> v[1] >> comma) && comma == ',' &&
              static_cast<bool>(in >> v[2]);
    in >> std::ws;
    if (!ok || !in.eof() || !std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]))
        throw InputError(flag + " \"" + text + "\": expected three finite numbers X,Y,Z");
    return {v[0], v[1], v[2]};
}

CLI::Validator seedValidator() {
    // CLI11 would wrap "-1" around to 2^64 - 1 for an unsigned option.
    return CLI::Validator(
        [](std::string& text) {
            return text.find('-') == std::string::npos
                       ? std::string()
                       : "a seed is an integer in [0, 2^64 - 1], got " + text;
        },
        "SEED");
}

CLI::Option* addSeedOption(CLI::App& app, uint64_t& seed, const std::string& description,
                           const std::string& flag) {
    return app.add_option(flag, seed, description + " (integer >= 0)")
        ->default_val(0)
        ->check(seedValidator());
}

Vec3 parseDirection(const std::string& text, const std::string& flag) {
    const Vec3 v = parseVec3(text, flag);
    const double largest = std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
    if (!(largest > 0)) throw InputError(flag + " \"" + text + "\" must be a non-zero vector");
    return normalizeAnyLength(v);
}

// Row `row` of PAIRS as a unit vector; inputs may be float32, so a deviation
// from unit length up to 1e-3 is accepted and normalised away.
Vec3 unitVectorAt(const NpyMatrix& m, size_t row, size_t col, const std::string& path) {
    const Vec3 v{m(row, col), m(row, col + 1), m(row, col + 2)};
    const double len = length(v);
    if (!isFinite(v) || !(std::fabs(len - 1.0) <= 1e-3)) {
        std::ostringstream msg;
        msg << path << ": row " << row << ": " << (col == 0 ? "wi" : "wo") << " = " << v
            << " is not a unit vector (length must be within 1e-3 of 1)";
        throw InputError(msg.str());
    }
    return v / len;
}

}  // namespace weft::cmd
