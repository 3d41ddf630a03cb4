// weft/yarn/yarn_appearance.h — the colour a yarn looks, and the fiber colour
// C_TT that gives a colour one wants to see (docs/colour.md, "Colour by
// appearance").
//
// The colour one sets in a scene is the fiber's C_TT, the colour of one pass
// through a fiber. Multiple scattering raises it to a power (a path with k TT
// events weighs C_TT^k), so a yarn looks darker and more saturated than its
// C_TT: C_TT (0.85, 0.55, 0.3) renders dark brown. The appearance of a yarn
// is defined under a standard light, a uniform white sky (radiance 1 from
// every direction), as the share of the light that meets the ply's fibers
// which they send back out, per channel:
//
//   A_c = integral over wi of (E_R,c + E_M,c)(wi) cos(theta_i)
//         / integral over wi of (1 - P(T|wi)) cos(theta_i),
//
// wi over the hemisphere above the ply's surface (yarn frame, n = +z), E the
// integrals of S_R and S_M over wo (yarn_integrals.h), as the renderer
// evaluates them (energy calibration and guard included). T is left out on
// both sides: the light that passes the ply untouched shows what lies behind
// it, not the yarn. A white lossless fiber gives A = 1, so A is a colour in
// [0, 1] like any albedo; it is linear (the scene's "appearance" is given in
// sRGB and converted before it gets here).
//
// Channel c of a model depends on C_TT,c alone (the colour functions, the
// calibration by colour and the energy guard are all per channel), so a table
// of greys serves every colour (appearance_table.h).
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "weft/core/rgb.h"
#include "weft/yarn/appearance_table.h"
#include "weft/yarn/yarn_bsdf.h"
#include "weft/yarn/yarn_model.h"

namespace weft {

// A_c of one model of one colour (the formula above), by a product
// Gauss-Legendre rule over wi (4-point panels in theta, uniform in phi) and
// yarn_integrals' rule over wo; `refinement` multiplies the wi nodes (the
// tests check that 1 agrees with 2). Deterministic at any thread count.
Rgb yarnAppearance(const YarnBsdf& bsdf, int refinement = 1);

// A conditioned model's appearance table (appearance_table.h): forColour at
// each of `nodes` greys over its colour range, about 0.3 s per node on 2
// cores. Where the fitted model's appearance does not darken with C_TT (its
// own error, at the dark end), each channel is replaced by the closest
// non-increasing sequence (pool adjacent violators); `largestAdjustment`
// gets the largest change. InputError naming `source` for a model that is
// not conditioned.
AppearanceTable computeAppearanceTable(const YarnModel& conditioned, const std::string& source,
                                       int nodes = AppearanceTable::kDefaultNodes,
                                       double* largestAdjustment = nullptr);

// What weft yarn appearance prints (docs/cli.md): a colour model's reach
// (its darkest and brightest appearance per channel, linear and sRGB) and,
// given an sRGB appearance, the C_TT that gives it, or, given a C_TT, its
// appearance; either with the appearance evaluated directly at that C_TT
// (yarnAppearance, not the table) as a check. The table is the model's, or
// computed for a model file older than version 4. InputError naming `source`
// for a model of one colour, naming `appearanceField` for an appearance out
// of reach and `cTTField` for a C_TT outside the colour range.
nlohmann::json appearanceReport(const YarnModel& model, const std::string& source,
                                const std::optional<Rgb>& srgbAppearance,
                                const std::optional<Rgb>& cTT,
                                const std::string& appearanceField = "--appearance",
                                const std::string& cTTField = "--c-tt");

}  // namespace weft
