#include "weft/yarn/material_preset.h"

#include <string>

#include "weft/core/error.h"

namespace weft {

const std::vector<MaterialPreset>& materialPresets() {
    // Paper Table 3 (docs/design.md 3): N, rho, alpha; C_R; C_TT; beta_R, beta_TT, gamma_TT.
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

YarnPoint yarnPointOf(const MaterialPreset& preset) {
    return {preset.ply.fibers,     preset.ply.density,     preset.ply.twist,
            preset.fiber.betaRDeg, preset.fiber.betaTTDeg, preset.fiber.gammaTTDeg,
            preset.fiber.cR};
}

}  // namespace weft
