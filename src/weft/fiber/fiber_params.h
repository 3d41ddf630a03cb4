// weft/fiber/fiber_params.h — fiber shading parameters and the Table 3 presets.
//
// Parameters of the Khungurn et al. (2015) fiber model (paper eq. 2-4,
// DESIGN.md 3):
//   c_r          [r,g,b] in [0,1]  Schlick reflectance at normal incidence (C_R)
//   c_tt         [r,g,b] in [0,1]  transmission attenuation (C_TT)
//   beta_r_deg   (0, 90]           longitudinal width of R, degrees
//   beta_tt_deg  (0, 90]           longitudinal width of TT, degrees
//   gamma_tt_deg (0, 90]           azimuthal width of TT, degrees (kappa = 1/gamma^2)
// JSON form: {"c_r":[r,g,b],"c_tt":[r,g,b],"beta_r_deg":x,"beta_tt_deg":x,"gamma_tt_deg":x};
// unknown keys are an error. A material preset adds the ply geometry
// (N, rho, alpha) of the paper's Table 3.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "weft/core/rgb.h"
#include "weft/ply/ply.h"

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

struct MaterialPreset {
    std::string_view name;
    FiberParams fiber;
    PlyParams ply;
};

// The five materials of the paper's Table 3 (fleece, silk, polyester, cotton, gabardine).
const std::vector<MaterialPreset>& materialPresets();
// Throws InputError listing the known names when `name` is unknown.
const MaterialPreset& findMaterialPreset(std::string_view name);

}  // namespace weft
