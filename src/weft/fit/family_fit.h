// weft/fit/family_fit.h — fitting a family model (yarn/family_model.h) to a
// family gather (gather/family.h): `weft fit family` (docs/family.md).
//
// The steps of a colour-conditioned fit (fit.h), over many yarns at once:
//   1. T network on every yarn's P(T | wi), its N, rho, alpha as inputs: a
//      yarn drawn uniformly per sample, then its incident bin in proportion
//      to its path counts (restarts as for T).
//   2. The colour functions (fit/colour_basis.h) from the records of up to
//      kFamilyBasisYarns yarns spread over the family, pooled.
//   3. M network on every yarn's records, its nine parameters as inputs: a
//      yarn drawn uniformly per sample, then cell and C_TT as in a colour
//      fit. Each yarn's few paths make noisy targets; the mean-squared loss
//      averages them over neighbouring yarns (its minimum is the mean).
//   4. The masking term: one linear least-squares fit over the yarns (up to
//      kFamilyMaskingYarns, spread) of coefficients linear in the
//      parameters (family_model.h), against each yarn's RDM_R.
//   5. The energy calibration (family_calibration.h): one fit over up to
//      kFamilyCalibrationYarns yarns, its coefficients linear in the yarn's
//      parameters, so that it follows them as the networks do; R's only
//      unless calibrateM.
//   6. The sampling lobe (fit.h step 5) of the yarn at the box's centre.
// With `recalibrate` set, the fit keeps that model and redoes step 5 only
// (for a model fitted before the calibration existed, or at another degree).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>

#include "weft/fit/family_calibration.h"
#include "weft/fit/fit.h"
#include "weft/gather/family.h"
#include "weft/yarn/family_model.h"

namespace weft {

// Yarns that the colour functions and the masking fit read.
inline constexpr int kFamilyBasisYarns = 32;
inline constexpr int kFamilyMaskingYarns = 512;
inline constexpr int kFamilyCalibrationDegree = 6;

struct FamilyFitOptions {
    FitConfig config = defaultConfig();
    ColourRange range{0.3, 0.999};
    int functions = 6;
    uint64_t seed = 0;
    bool quiet = false;
    std::optional<FamilyModel> recalibrate;  // refit this model's calibration only
    // Calibrate M too (family_calibration.h); off by default: measured, it
    // made the albedo worse at held-out yarns and at cotton (docs/family.md).
    bool calibrateM = false;

    // A family's defaults: wider networks (T 16-16: its inputs include the
    // ply's geometry; M 32-32-32: one network for every yarn, measured
    // against 21-21-21 in docs/family.md), four times the M steps of a
    // one-yarn fit, an energy calibration of degree kFamilyCalibrationDegree.
    static FitConfig defaultConfig();
};

struct FamilyFitResult {
    FamilyModel model;
    LossCurve tLoss, mLoss;
};

// InputError naming the yarn's folder when a point's data are damaged, or the
// option out of range.
FamilyFitResult fitFamilyModel(const FamilyGather& gather, const FamilyFitOptions& options);

}  // namespace weft
