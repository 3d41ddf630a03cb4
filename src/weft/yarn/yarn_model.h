// weft/yarn/yarn_model.h — the fitted neural yarn model and its model.json file.
//
// One self-describing file per ply material (docs/design.md 6, issue 5), format
// "weft-yarn-model" version 1, documented key by key in docs/model-format.md:
//   fiber     the fiber parameters (FiberParams JSON)
//   ply       {"fibers": N, "density": rho, "twist": alpha}
//   t_net     P(T | wi): 3-7-7-1, PReLU, sigmoid output (paper 5.2)
//   m_net     S_M(wi, wo): 6-21-21(-21)-3, PReLU, exp output (paper 5.3)
//   r_lobe    the analytic R lobe (paper eq. 8) and its optional masking term
//   sampling  kappa_R, beta_M, gamma_M, kappa_M (paper eq. 9-11)
//   energy_calibration  per-direction energy scales of R and M
//             (energy_calibration.h), or null / absent for none
//   fit       errors and provenance of the fit (free-form numbers and strings)
//   ablation  optional: "naive" or "no_r_lobe" for the ablations of paper
//             Fig. 5 (YarnAblation below); absent for the full model
//   colour    version 2 and 3, optional: a colour-conditioned model (fitted
//             from one any-colour gather, docs/colour.md) for any C_TT in
//             "c_tt_range": m_net then has 3K outputs and an identity output,
//             and "functions" holds the K colour functions (yarn/colour_basis.h).
//             forColour(C_TT) gives the ordinary model of one colour.
//             Version 3: its energy_calibration may be the by-colour form
//             (ColourCalibration: "c_tt" node colours and per node the rows
//             of r and m).
//   appearance  version 4, optional, conditioned models only: the colour the
//             yarn looks at greys across the colour range (appearance_table.h),
//             which "appearance" in a scene inverts to a C_TT.
//   exit_offset  version 5, optional, models of one colour only: where the
//             ply's multiply scattered light leaves it relative to where it
//             entered (exit_offset_table.h; docs/exit-point.md).
// Version 1 to 4 files still load; the writer writes version 1 unless the
// model is conditioned, 2 for a conditioned model without a calibration, 3
// with one, 4 with an appearance table, 5 with an exit-offset table.
// Networks: {"layers": [{"weight": [[in numbers] x out rows], "bias": [out],
// "prelu": [out] or null}, ...], "output": "sigmoid" | "exp" | "identity"};
// layer l computes y = W x + b, then the PReLU when present. Network inputs
// are unit vectors in the yarn frame (t, b, n): wi for t_net, (wi, wo) for m_net.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "weft/core/rgb.h"
#include "weft/fiber/fiber_params.h"
#include "weft/ply/ply.h"
#include "weft/yarn/appearance_table.h"
#include "weft/yarn/colour_basis.h"
#include "weft/yarn/energy_calibration.h"
#include "weft/yarn/exit_offset_table.h"
#include "weft/yarn/network.h"

namespace weft {

inline constexpr const char* kYarnModelFormat = "weft-yarn-model";
inline constexpr int kYarnModelVersion = 5;  // the newest; 1 to 4 are read too

// The R lobe (paper eq. 8): (1 - P(T|wi)) S_f(wi~, wo~) in the surface fiber
// frame (tangent tilted by tiltDeg = atan(pi alpha) about n), zero unless both
// wi and wo are in the upper hemisphere; optionally times a fitted masking
// term m(wi, wo) (see yarn_lobes.h for its form).
struct RLobeParams {
    double tiltDeg = 0;           // in [0, 90)
    std::vector<double> masking;  // empty: plain eq. 8 (JSON null); else kMaskingCoefficients numbers

    // InputError naming the model.json key ("r_lobe.tilt_deg") and its range.
    void validate() const;
};

// Lobe selection and the M sampling lobe (paper eq. 9-11, docs/design.md 7).
struct SamplingParams {
    double kappaR = 0.5;   // share of R in the non-T energy, in [0, 1]
    double betaMDeg = 20;  // longitudinal width of the M lobe, degrees in (0, 90]
    double gammaMDeg = 40; // azimuthal width of the M lobe (von Mises kappa = 1/gamma^2), degrees in (0, 180]
    double kappaM = 0.5;   // weight of the cone lobe against the uniform sphere, in [0, 1]

    // InputError naming the model.json key ("sampling.kappa_r") and its range.
    void validate() const;
};

// Which model of paper Fig. 5 a file holds (docs/fit.md, "Ablations").
//   None     the full model: S_T + S_R + S_M.
//   Naive    one network over the whole RDM (paper Fig. 5, "naive", after
//            [SRRW21]): P(T) = 0 and S_R = 0 everywhere; m_net alone is
//            the BSDF, fitted to RDM_R + RDM_M + the T energy as a density
//            in the outgoing bin of -wi. t_net is stored (the format needs
//            one) but never read.
//   NoRLobe  S_R = 0; m_net is fitted to RDM_R + RDM_M, T as usual.
enum class YarnAblation { None, Naive, NoRLobe };
// The file's names: "none" (written as an absent key), "naive", "no_r_lobe".
const char* yarnAblationName(YarnAblation ablation);
// The names a user types (`weft fit --ablation`, Python's fit(ablation=)):
// "" or "none", "naive", "no-r-lobe". InputError naming `what` and the allowed
// names otherwise.
YarnAblation parseYarnAblation(const std::string& name, const std::string& what);

struct YarnModel {
    FiberParams fiber;
    PlyParams ply;
    NetworkWeights tNet;  // 3 inputs, 1 output
    NetworkWeights mNet;  // 6 inputs, 3 outputs (3K, identity output, when conditioned)
    RLobeParams rLobe;
    SamplingParams sampling;
    EnergyCalibration calibration;  // empty: none
    nlohmann::json fit = nlohmann::json::object();  // errors and provenance, written as is
    YarnAblation ablation = YarnAblation::None;
    // A colour-conditioned model: the colour functions of its M network, and
    // (version 3, optional) its energy calibration by colour; such a model's
    // `calibration` is empty, forColour() makes it from colourCalibration.
    std::optional<ColourBasis> colour;
    ColourCalibration colourCalibration;
    // A conditioned model's appearance at greys spanning its colour range
    // (version 4; computeAppearanceTable in yarn_appearance.h makes it).
    std::optional<AppearanceTable> appearance;
    // Where M light leaves the ply (version 5; `weft fit` makes it from the
    // gather's exit offsets when its configuration asks). None: it leaves
    // where it entered, as in the paper.
    std::optional<ExitOffsetTable> exitOffset;

    // What the renderer needs beyond the file's syntax (InputError naming the
    // key): the networks' shapes (t_net 3 -> 1, m_net 6 -> 3) and output
    // functions (sigmoid, so that P(T) is a probability; exp, so that S_M >= 0),
    // and the R lobe and sampling parameters' ranges. The reader and YarnBsdf
    // both call it.
    void validate() const;

    // The ordinary model of one fiber colour C_TT (each channel within the
    // model's colour range): fiber.cTT = cTT, and the colour functions at cTT
    // folded into m_net's last layer (foldColourIntoNetwork), so that it
    // renders exactly like a model fitted for that colour alone and costs the
    // same. InputError naming `what` for a model that is not conditioned or a
    // channel out of its colour range (never a silent clamp).
    YarnModel forColour(const Rgb& cTT, const std::string& what) const;
    // The colour a conditioned model is drawn at when a yarn gives none: its
    // gathered C_TT, each channel moved into the colour range (a range fitted
    // narrower than the gathered colour, e.g. polyester's green 0 with
    // [0.3, 0.999]).
    Rgb ownColourInRange() const;

    // Whether S_T (the T network) and S_R (the analytic lobe) are part of the BSDF.
    bool hasTransmissionLobe() const { return ablation != YarnAblation::Naive; }
    bool hasReflectionLobe() const { return ablation == YarnAblation::None; }
};

// JSON document of a model (the layout above).
nlohmann::json yarnModelToJson(const YarnModel& model);
// Validating reader: InputError naming `source` and the JSON path of the
// offending field ("m_net.layers[1].weight: expected 21 rows of 21 numbers")
// for a missing key, an unknown key, a wrong shape, a non-finite number, an
// out-of-range parameter, a wrong format name or an unknown version.
YarnModel yarnModelFromJson(const nlohmann::json& j, const std::string& source);

// File forms: the reader names the file (and the JSON parse error's byte
// offset for malformed JSON); the writer is atomic (writeFileAtomic) and first
// checks the document with the reader, so a non-finite weight is an InputError
// rather than a null in the file.
YarnModel loadYarnModel(const std::string& path);
void saveYarnModel(const YarnModel& model, const std::string& path);

}  // namespace weft
