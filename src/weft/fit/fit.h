// weft/fit/fit.h — fitting the neural yarn model to a gathered RDM (weft fit).
//
// Paper 4.1-4.4, 5.2-5.3, docs/design.md 6. From a gather directory:
//   1. T network (3-7-7-1, PReLU, sigmoid) on P(T | wi): incident bins are
//      drawn in proportion to their path counts (bins with few paths weigh
//      less, exactly as their variance says), wi uniform in solid angle
//      inside the bin, MSE, Adam.
//   2. R lobe: plain eq. 8 with P(T|wi) from the T network, and optionally a
//      masking term m(wi, wo) (yarn_lobes.h) fitted to RDM_R by linear least
//      squares on the coarse error grid.
//   3. M network (6-21-21-21-3 by default, PReLU, exp) on RDM_M: incident bins
//      uniform, outgoing bins in proportion to their solid angle (the weights
//      of the error metric), directions uniform in solid angle inside the bins
//      ("jitter"); MSE or MSE on log(1 + x); Adam with an exponentially
//      decaying learning rate. Each batch is split into a fixed number of
//      chunks whose gradients are summed in order, so the result depends on
//      the seed only, not on the thread count.
//   4. Energy calibration (energy_calibration.h): smooth per-direction scales
//      of R and M so that their integrals over wo match the RDM's energies at
//      every incident bin with enough paths (log-ratio least squares weighted
//      by path count; the degree is lowered when there are fewer than 4 bins
//      per coefficient).
//   5. Sampling: kappa_R = R energy / (R + M energy) of the model; beta_M,
//      gamma_M, kappa_M minimise the second moment sum f_M^2 / pdf_M (the
//      variance of the M estimator) over the RDM grid, by Nelder-Mead.
//   6. (colour models) the appearance table; 7. (optional, config
//      "exit_offset") where M light leaves the ply: the gather's exit offsets
//      merged into ExitOffsetTable::defaultEdges() (docs/exit-point.md).
// Errors use the one coarse-grid metric (metrics.h). The steps live in
// train.h (1, 3), masking_fit.h (2), calibration.h (4), sampling_fit.h (5);
// the configuration in fit_config.h, the model's maps in model_maps.h. This
// header gathers them and declares the orchestration (fit.cpp).
//
// Ablations (paper Fig. 5, docs/fit.md): the same five steps against the
// target of ablationTarget() below, with the parts the variant lacks left
// out: naive (no T network, no R lobe, the M network on the whole RDM) and
// no-R-lobe (T as usual, no R lobe, the M network on RDM_R + RDM_M).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "weft/fit/calibration.h"
#include "weft/fit/colour_basis.h"
#include "weft/fit/colour_targets.h"
#include "weft/fit/fit_config.h"
#include "weft/fit/masking_fit.h"
#include "weft/fit/model_maps.h"
#include "weft/fit/sampling_fit.h"
#include "weft/fit/train.h"
#include "weft/gather/rdm_io.h"
#include "weft/yarn/yarn_model.h"

namespace weft {

struct FitReport {
    double tRmse = 0;            // path-count-weighted RMS error of P(T|wi) over incident bins
    double tRmseUnweighted = 0;  // plain RMS over incident bins
    double mRelL2 = 0;           // coarse-grid relative L2 (metrics.h) of M against the RDM
    double rRelL2 = 0;           // the same for the R lobe as stored in the model
    double mRelL2Uncalibrated = 0, rRelL2Uncalibrated = 0;  // before step 4
    nlohmann::json calibration;  // step 4's summary (fitEnergyCalibration), null when off
    double rRelL2Eq8 = 0;        // plain eq. 8 (no masking)
    double rRelL2Masked = 0;     // with the fitted masking term (NaN when not fitted)
    double rEnergyRatio = 0;     // RDM_R energy / plain eq. 8 energy
    double mSecondMoment = 0;    // sum f^2/pdf of the fitted M lobe, relative to the uniform sphere
    double tSeconds = 0, mSeconds = 0, seconds = 0;
    double mSamplesPerSecond = 0;
    LossCurve tLoss, mLoss;
    // A conditioned fit: the colour functions' truncation error and M's error
    // at test colours against the recoloured RDM (null otherwise).
    nlohmann::json colour;
};

// A colour-conditioned fit (docs/colour.md): T and R as usual, the M network
// for every C_TT in `range` from the recorded paths of an any-colour gather
// (gather/colour_paths.h), an energy calibration by colour (fitColourCalibration,
// calibration.h; none when config.calibrationDegree < 0), the sampling lobe
// fitted at the gathered colour.
struct ColourFitOptions {
    ColourRange range;
    int functions = 6;                                // K colour functions, 2..12
    const std::vector<ColourPath>* paths = nullptr;  // the gather's records
};

struct FitResult {
    YarnModel model;
    FitReport report;
};

// Fits every part of the model; `ablation` (recorded in the model and in its
// fit block) fits one of the variants of paper Fig. 5 instead.
FitResult fitYarnModel(const RdmData& rdm, const FitConfig& config, uint64_t seed, bool quiet,
                       YarnAblation ablation = YarnAblation::None,
                       const ColourFitOptions* colour = nullptr);

// The colours at which a conditioned fit reports M's error: the five
// Table 3 colours and the range's ends and middle (grey), clamped into it.
std::vector<Rgb> colourFitTestColours(const ColourRange& range);

// The RDM as an ablated model sees it: what each of its parts is fitted to
// and measured against. None: `rdm` unchanged. NoRLobe: rdmM = RDM_R + RDM_M,
// rdmR = 0, P(T) kept. Naive: also P(T) = 0, and the T energy added to rdmM
// as a density, P(T | bin i) / (solid angle of bin o), grey, in the outgoing
// bin o = transmissionOutgoingBin(bins, i) (S_T's direction wo = -wi,
// docs/design.md 7); so for every incident bin the target's integral over wo,
// sum_o rdmM dOmega_o, is P(T) + E_R + E_M of the gather.
RdmData ablationTarget(const RdmData& rdm, YarnAblation ablation);
// The RDM as a model with an exit-offset table sees it (docs/exit-point.md):
// RDM_M with wo in the exit frame (the gather's rdm_m_exit.npy), so that its M
// lobe does not spread the light around the ply a second time. InputError
// naming the gather when it has none.
RdmData exitFrameTarget(const RdmData& rdm);
// What `model` was fitted to and is measured against: ablationTarget() for an
// ablated model, exitFrameTarget() for one with an exit-offset table, else
// `rdm` itself.
RdmData fitTarget(const RdmData& rdm, const YarnModel& model);
// The outgoing bin of -wi for wi at the centre of incident bin i.
size_t transmissionOutgoingBin(const RdmBins& bins, size_t incidentBin);

// Steps 4 and 5 again on a fitted model (its networks and R lobe kept, its
// calibration replaced): for models fitted before the calibration existed or
// with another configuration. The fit record keeps the original entries and
// gets the new errors and a "recalibrated" entry. An ablated model is
// recalibrated against fitTarget(rdm, fitted) (its ablation's target, or M
// in the exit frame). A colour-conditioned model
// gets its calibration by colour again (fitColourCalibration) from `paths`,
// the recorded paths of the any-colour gather `rdm` (InputError without
// them), and the sampling lobe of its gathered colour.
FitResult recalibrateYarnModel(const YarnModel& fitted, const RdmData& rdm, const FitConfig& config,
                               bool quiet, const std::vector<ColourPath>* paths = nullptr);

// The report next to a model: errors.json, loss.png, and RDM-vs-fit slice
// PNGs for a few incident directions; `reference` (an independent gather of
// the same material) adds the errors against it and the noise floor. For an
// ablated model pass ablationTarget() of both gathers.
void writeFitReport(const FitResult& fit, const RdmData& rdm, const RdmData* reference,
                    const std::string& dir);
// The slice pictures of that report (and of `weft yarn check`): for a few
// incident directions, the RDM (left) against the model's map (right), one
// PNG per component, slice-{m,r}-thetaTT-phiPPP.png in `dir`.
void writeSliceComparisons(const std::string& dir, const RdmData& rdm,
                           const std::vector<float>& rMap, const std::vector<float>& mMap);

}  // namespace weft
