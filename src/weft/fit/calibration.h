// weft/fit/calibration.h — step 4 of the fit: the energy calibration
// (yarn/energy_calibration.h holds its form and its evaluation).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <vector>

#include "weft/core/vec.h"
#include "weft/gather/gather.h"
#include "weft/gather/rdm_io.h"
#include "weft/yarn/energy_calibration.h"
#include "weft/yarn/yarn_model.h"

namespace weft {

// Weighted least squares for one channel: coefficients minimising
// sum_i weight_i (sum_k c_k basis_k(wi_i) - logRatio_i)^2 (column-pivoted QR).
std::vector<double> fitLogPolynomial(const std::vector<Vec3>& wi,
                                     const std::vector<double>& logRatio,
                                     const std::vector<double>& weight, int degree);

// Step 4: the energy calibration of `model` (its calibration is ignored) on
// incident bins with at least kCalibrationMinPaths paths; `summary` (optional)
// gets the albedo errors before and after and the range of the scales.
inline constexpr int64_t kCalibrationMinPaths = 100;
EnergyCalibration fitEnergyCalibration(const YarnModel& model, const RdmData& rdm, int degree,
                                       int threads, nlohmann::json* summary = nullptr);

// The energy calibration by colour of a colour-conditioned model
// (ColourCalibration, yarn/energy_calibration.h): kColourCalibrationNodes
// grey node colours uniform in u = sqrt(-ln C_TT) over the model's colour
// range, and at each, fitEnergyCalibration of the model of that grey
// (model.forColour) against the RDM of that grey recoloured from the any-colour
// gather's recorded `paths` (fit/colour_targets.h; P(T) and the counts are
// `rdm`'s, which do not depend on the colour). `summary` (optional) gets each
// node's colour and albedo errors before and after.
inline constexpr int kColourCalibrationNodes = 7;
// The node colours: greys uniform in u = sqrt(-ln C_TT) from range.lo to range.hi.
std::vector<double> colourCalibrationNodes(const ColourRange& range);
ColourCalibration fitColourCalibration(const YarnModel& model, const RdmData& rdm,
                                       const std::vector<ColourPath>& paths, int degree,
                                       int threads, nlohmann::json* summary = nullptr);

}  // namespace weft
