// weft/fit/calibration.h — step 4 of the fit: the energy calibration
// (yarn/energy_calibration.h holds its form and its evaluation).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <vector>

#include "weft/core/vec.h"
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

}  // namespace weft
