// weft/fiber/fiber_params.h — fiber shading parameters.
//
// Parameters of the Khungurn et al. (2015) fiber model (paper eq. 2-4,
// docs/design.md 3):
//   c_r          [r,g,b] in [0,1]  Schlick reflectance at normal incidence (C_R)
//   c_tt         [r,g,b] in [0,1]  transmission attenuation (C_TT)
//   beta_r_deg   [0.1, 90]         longitudinal width of R, degrees
//   beta_tt_deg  [0.1, 90]         longitudinal width of TT, degrees
//   gamma_tt_deg [0.1, 90]         azimuthal width of TT, degrees (kappa = 1/gamma^2)
// JSON form: {"c_r":[r,g,b],"c_tt":[r,g,b],"beta_r_deg":x,"beta_tt_deg":x,"gamma_tt_deg":x};
// unknown keys are an error. The paper's Table 3 materials (these and the ply
// geometry) are the presets of yarn/material_preset.h.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>

#include "weft/core/rgb.h"

namespace weft {

struct FiberParams {
    Rgb cR, cTT;
    double betaRDeg = 0, betaTTDeg = 0, gammaTTDeg = 0;

    // Throws InputError naming `source` (a file or "preset NAME") and the field.
    void validate(const std::string& source = "fiber parameters") const;

    // Strict JSON reading (core/json_reader.h): every key required, unknown keys
    // rejected, values validated; errors name `source` and the JSON path under
    // `path` (the object's own path, "fiber" inside model.json).
    static FiberParams fromJson(const nlohmann::json& j, const std::string& source,
                                const std::string& path = "");
    static FiberParams fromJsonFile(const std::string& path);
    nlohmann::json toJson() const;
};

}  // namespace weft
