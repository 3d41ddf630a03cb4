// weft/fit/model_maps.h — a yarn model's parts on an RDM grid, for the fit's
// errors and reports.
//
// Evaluated at bin centres, in the layout of the gather's arrays (gather.h):
// P(T | wi) (TI, PI); R and M (TI, PI, TO, PO, 3), calibration applied, no
// energy guard (the fit measures the model as fitted). An ablated model's
// missing parts are zero maps. The maps are built while the model is being
// fitted (the R map before the M network exists), so they evaluate its parts
// rather than a YarnBsdf: P(T) through the renderer's own float inference
// (yarn/fixed_mlp.h), R through yarn/yarn_lobes.h's RLobe, and M through the
// trainer's batched network (fit/mlp.h), which computes the same function.
#pragma once

#include <vector>

#include "weft/gather/rdm.h"
#include "weft/yarn/colour_basis.h"
#include "weft/yarn/network.h"
#include "weft/yarn/yarn_model.h"

namespace weft {

// P(T | wi) of a T network (3 -> 1) at the incident bin centres.
std::vector<double> transmissionMap(const NetworkWeights& tNet, const RdmBins& bins);

std::vector<double> modelTransmissionMap(const YarnModel& model, const RdmBins& bins);
std::vector<float> modelReflectionMap(const YarnModel& model, const RdmBins& bins);
std::vector<float> modelMultipleScatteringMap(const YarnModel& model, const RdmBins& bins);
// M of a colour-conditioned network (yarn/colour_basis.h) for one C_TT.
std::vector<float> conditionedMultipleScatteringMap(const NetworkWeights& mNet,
                                                    const ColourBasis& basis, const RdmBins& bins,
                                                    const Rgb& cTT);

}  // namespace weft
