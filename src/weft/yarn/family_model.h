// weft/yarn/family_model.h — one model for every yarn of a box of yarn
// parameters (issue 42; docs/family.md, docs/model-format.md).
//
// A family model is fitted (fit/family_fit.h) to a family gather
// (gather/family.h): the walks of many yarns spread over a FamilyBox. Its
// networks take the yarn's parameters as inputs, each mapped from its
// range in the box to [-1, 1] (FamilyBox::normalised, q below):
//   t_net  P(T | wi; N, rho, alpha): 6 -> 1, sigmoid. Direct transmission
//          depends on the ply's geometry only.
//   m_net  the colour coefficients of S_M (yarn/colour_basis.h) for
//          (wi, wo; N, rho, alpha, beta_R, beta_TT, gamma_TT, C_R r, g, b):
//          15 -> 3K, identity. C_TT stays free, as in a colour model.
//   r_lobe eq. 8 follows the parameters analytically (the fiber's beta_R and
//          C_R, the tilt atan(pi alpha), P(T) from t_net); its masking
//          coefficients (yarn_lobes.h) are linear in (1, q_N, ..., q_gammaTT).
//   energy_calibration  (version 2; fit/family_calibration.h) the energy
//          calibration by colour (yarn/energy_calibration.h) of every yarn:
//          its coefficients linear in features of the yarn and the channel.
// at(p) makes the ordinary colour model of the yarn p: the constant inputs
// folded into the first layers' biases (foldConstantInputs), so that it has
// the networks' shapes of a model fitted for p alone and renders at the same
// cost; the renderer then builds its tables for it as for any model.
//
// File: {"format": "weft-family-model", "version": 1 or 2, "box", "colour",
// "t_net", "m_net", "r_lobe": {"masking": null or {"form":
// "symmetric-quadratic", "features": "linear", "coefficients": 4 rows of 7}},
// "energy_calibration" (version 2 only): null or {"form":
// "log-polynomial-by-colour", "features": "linear-by-channel", "degree": d,
// "c_tt": node colours, "r": (d + 1)^2 rows of 8, "m": per node (d + 1)^2
// rows of 8}, "sampling", "fit"}. Version 1 is written when there is no
// calibration, so that older readers read such files.
#pragma once

#include <array>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "weft/core/family_box.h"
#include "weft/yarn/colour_basis.h"
#include "weft/yarn/network.h"
#include "weft/yarn/yarn_lobes.h"
#include "weft/yarn/yarn_model.h"

namespace weft {

inline constexpr const char* kFamilyModelFormat = "weft-family-model";
inline constexpr int kFamilyModelVersion = 2;

// The networks' inputs: the directions, then the normalised parameters.
inline constexpr int kFamilyTInputs = 3 + 3;                       // wi; N, rho, alpha
inline constexpr int kFamilyMInputs = 6 + FamilyBox::kDimensions;  // wi, wo; all nine
// The masking coefficients' features: 1 and the six normalised parameters
// other than C_R (which scales eq. 8 itself).
inline constexpr int kFamilyMaskingFeatures = 7;
std::array<double, kFamilyMaskingFeatures> familyMaskingFeatures(const FamilyBox& box,
                                                                 const YarnPoint& p);

// The energy calibration's features of the yarn p for channel c: 1, the six
// normalised non-colour parameters and the channel's normalised C_R (a
// channel's energies depend on its own C_R and C_TT only: the walks'
// weights are products of per-channel factors, gather/colour_paths.h).
inline constexpr int kFamilyCalibrationFeatures = 8;
std::array<double, kFamilyCalibrationFeatures> familyCalibrationFeatures(const FamilyBox& box,
                                                                         const YarnPoint& p,
                                                                         int channel);

// The energy calibration of every yarn of the box: the yarn p's calibration
// by colour (ColourCalibration, one EnergyCalibration per node colour) has,
// for channel c, the coefficients
//   r_c[k] = sum_l r[k, l] f_l(p, c),   m_c[k] at node g = sum_l m[g][k, l] f_l(p, c)
// with f = familyCalibrationFeatures: log s is linear in the features, so
// the calibration follows the parameters and costs nothing to build.
struct FamilyCalibration {
    int degree = -1;                     // -1: none
    std::vector<double> cTT;             // M's node colours, strictly increasing in (0, 1]
    std::vector<double> r;               // r[k * kFamilyCalibrationFeatures + l]
    std::vector<std::vector<double>> m;  // per node, as r

    bool empty() const { return degree < 0; }
    // InputError starting with `what` unless the shapes agree and every
    // coefficient is finite.
    void validate(const std::string& what) const;
    // The calibration by colour of the yarn p (empty when this is).
    ColourCalibration at(const FamilyBox& box, const YarnPoint& p) const;
};

struct FamilyModel {
    FamilyBox box;
    NetworkWeights tNet;  // kFamilyTInputs -> 1, sigmoid
    NetworkWeights mNet;  // kFamilyMInputs -> 3K, identity
    ColourBasis colour;
    // masking[k * kFamilyMaskingFeatures + l]: masking coefficient k of the
    // yarn p is sum_l masking[k, l] feature_l(p). Empty: plain eq. 8.
    std::vector<double> masking;
    // The fitted sampling lobe (paper eq. 9-11) of the box's centre: what
    // the optional fitted sampler uses (the default tabulated one is built
    // per yarn from its own model).
    SamplingParams sampling;
    FamilyCalibration calibration;
    nlohmann::json fit = nlohmann::json::object();  // errors and provenance

    // InputError naming the key: the box, the networks' shapes and outputs,
    // the masking rows, the sampling block; and that the yarn at the box's
    // centre is a model the renderer runs.
    void validate() const;
    // The ordinary colour model of the yarn p (fiber C_TT 0.5 grey, the colour
    // a scene that gives none sees), with its calibration by colour: InputError naming `what`, the
    // field, its value and the box when p is outside the box.
    YarnModel at(const YarnPoint& p, const std::string& what) const;
    // The box's centre (N rounded).
    YarnPoint centre() const;
};

nlohmann::json familyModelToJson(const FamilyModel& model);
// Strict reader: InputError naming `source` and the JSON path.
FamilyModel familyModelFromJson(const nlohmann::json& j, const std::string& source);
FamilyModel loadFamilyModel(const std::string& path);
// Atomic; the document is read back first, so a non-finite weight is an
// InputError rather than a null in the file.
void saveFamilyModel(const FamilyModel& model, const std::string& path);
// Whether a model document says it is a family model ("format").
bool isFamilyModelDocument(const nlohmann::json& j);

// A model file as scenes read it (`weft render`, `weft scene`): a model of
// one yarn, or a family model whose yarns at() makes; its "format" decides.
struct ModelFile {
    std::string path;
    std::optional<YarnModel> single;
    std::optional<FamilyModel> family;

    // InputError naming the path (and the JSON path) for a bad file.
    static ModelFile load(const std::string& path);
    // The model of a yarn that gives `yarn` (or none): the model of one yarn
    // as it is, refusing a yarn; the family's yarn at `yarn`, requiring one.
    // Messages name `owner` (the yarn's entry, or --model) or `yarnWhat` (where
    // the yarn is given), and `yarnHint` says how to give one.
    YarnModel forYarn(const std::optional<YarnPoint>& yarn, const std::string& owner,
                      const std::string& yarnWhat, const std::string& yarnHint) const;
};

}  // namespace weft
