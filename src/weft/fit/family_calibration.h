// weft/fit/family_calibration.h — the energy calibration of a family model
// (yarn/family_model.h, FamilyCalibration): a step of `weft fit family`.
//
// A model fitted for one yarn ends with an energy calibration
// (calibration.h): per component, channel and incident direction, a smooth
// scale that makes the model's directional energies those of its RDM. A
// family has few paths per yarn (62,500 against 16M), so one yarn's RDM is
// too noisy to calibrate that yarn alone; the family's calibration is one
// fit over many yarns, with log s linear in the yarn's features
// (familyCalibrationFeatures) times the polynomial basis of wi:
//   log s_c(wi; p) = sum_k sum_l beta[k, l] basis_k(wi) f_l(p, c)
// for R (one system) and for M at each node colour (one system per node).
//
// The estimator: at so few paths per bin the log of a bin's RDM energy is
// biased low (E[log X] < log E[X]; about -1/(2n) for n paths), which a
// least-squares fit of log ratios (what calibration.h does with 16M paths)
// would carry into the scale. Instead each system is a Poisson regression
// with a log link, maximum likelihood by Newton's method:
//   minimise  sum_i n_i (mu_i - y_i log mu_i),  mu_i = E_i exp(x_i . beta)
// over the (yarn, channel, incident bin) points i with n_i paths, the
// model's energy E_i (no calibration) and the RDM's y_i. Its score
// sum n_i (mu_i - y_i) x_i is linear in the RDM, so noise does not bias it.
#pragma once

#include <Eigen/Dense>
#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <vector>

#include "weft/core/family_box.h"
#include "weft/fit/colour_targets.h"
#include "weft/gather/rdm.h"
#include "weft/yarn/family_model.h"

namespace weft {

// Yarns that the calibration reads (spread over the family), and the paths
// an incident bin needs to count.
inline constexpr int kFamilyCalibrationYarns = 96;
inline constexpr int64_t kFamilyCalibrationMinPaths = 20;
// The basis terms up to these degrees follow the yarn's features (R, M); the
// higher ones (the shape in wi) are one set of coefficients for every yarn.
// Every term times every feature extrapolates wildly at the box's faces
// (measured on cotton, at N 600 and beta_R 1: M energy off by up to 80 % at
// degree 6 with every term following the features, 50 % up to degree 2,
// against 10 % uncalibrated).
inline constexpr int kFamilyCalibrationFeatureDegreeR = 2;
inline constexpr int kFamilyCalibrationFeatureDegreeM = 0;

// One yarn's data: its parameters, its recorded R and M paths (any colour)
// and its paths per incident bin.
struct FamilyCalibrationYarn {
    YarnPoint point;
    const ColourTargets* r = nullptr;
    const ColourTargets* m = nullptr;
    const std::vector<int64_t>* count = nullptr;
};

// One point of a calibration system: a group's (a yarn's channel's)
// energies at an incident bin (a row of the basis matrix).
struct FamilyCalibrationPoint {
    int32_t bin = 0, group = 0;
    double paths = 0;  // n: the bin's paths
    double model = 0;  // E: the model's energy, uncalibrated (> 0)
    double rdm = 0;    // y: the RDM's
};
using CalibrationFeatures = std::array<double, kFamilyCalibrationFeatures>;

struct PoissonFit {
    std::vector<double> beta;  // beta[k * kFamilyCalibrationFeatures + l]
    int iterations = 0;
    // sum n |E s - y| / sum n y before (s = 1) and after (s clamped as at run time).
    double errorBefore = 0, errorAfter = 0;
};

// The Poisson regression above for points that come group by group (all
// points of a group consecutive): log s of a point is
// sum_k sum_l beta[k, l] basis(bin, k) features[group][l]; only the
// coefficients k * kFamilyCalibrationFeatures + l flagged in `active` are
// fitted (empty: all), the others stay 0.
PoissonFit fitPoissonLogLinear(const std::vector<FamilyCalibrationPoint>& points,
                               const Eigen::MatrixXd& basis,
                               const std::vector<CalibrationFeatures>& features,
                               const std::vector<bool>& active = {});

// The calibration of `model` (its own calibration is ignored) at `degree`
// (EnergyCalibration's polynomial degree): R's, and with
// `multipleScattering` M's at the node colours
// colourCalibrationNodes(model.colour.range()); without, M's scale is 1 (one
// node of zeros). `summary` (optional) gets
// the yarns, points, Newton iterations, and the energies' error against the
// yarns' RDMs before and after (PoissonFit).
FamilyCalibration fitFamilyCalibration(const FamilyModel& model,
                                       const std::vector<FamilyCalibrationYarn>& yarns,
                                       const RdmBins& bins, int degree, bool multipleScattering,
                                       int threads, bool quiet, nlohmann::json* summary = nullptr);

}  // namespace weft
