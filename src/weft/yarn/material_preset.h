// weft/yarn/material_preset.h — the paper's Table 3 materials: fiber and ply.
//
// A material preset names one of the five materials of the paper's Table 3
// (docs/design.md 3) and holds both halves of its row: the fiber shading
// parameters (C_R, C_TT, beta_R, beta_TT, gamma_TT; fiber/fiber_params.h)
// and the ply geometry (N, rho, alpha; ply/ply.h). It lives above fiber/ and
// ply/ so that neither depends on the other; the CLI (--preset), the Python
// module and the benchmarks look presets up here.
#pragma once

#include <string_view>
#include <vector>

#include "weft/core/family_box.h"
#include "weft/fiber/fiber_params.h"
#include "weft/ply/ply.h"

namespace weft {

struct MaterialPreset {
    std::string_view name;
    FiberParams fiber;
    PlyParams ply;
};

// The five materials of the paper's Table 3 (fleece, silk, polyester, cotton, gabardine).
const std::vector<MaterialPreset>& materialPresets();
// Throws InputError listing the known names when `name` is unknown.
const MaterialPreset& findMaterialPreset(std::string_view name);
// The preset's yarn parameters (a family model's point, core/family_box.h).
YarnPoint yarnPointOf(const MaterialPreset& preset);

}  // namespace weft
