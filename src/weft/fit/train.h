// weft/fit/train.h — steps 1 and 3 of the fit: the T and M networks (fit.h).
//
// Adam on mini-batches drawn from the RDM. Every batch is split into a fixed
// number of chunks whose gradients are summed in order, so a network depends
// on the seed only, not on the thread count.
//   T: incident bins drawn in proportion to their path counts, wi uniform in
//      solid angle inside the bin (config.jitter), MSE on P(T | wi);
//      `restarts` trainings from different seeds, the best (path-count-weighted
//      RMS error) is kept.
//   M: incident bins uniform, outgoing bins in proportion to their solid angle,
//      directions jittered inside the bins; the configured loss on RDM_M.
#pragma once

#include <tbb/task_arena.h>

#include <array>
#include <cstdint>
#include <vector>

#include "weft/core/family_box.h"
#include "weft/fit/colour_targets.h"
#include "weft/fit/fit_config.h"
#include "weft/gather/rdm_io.h"
#include "weft/yarn/colour_basis.h"
#include "weft/yarn/network.h"

namespace weft {

struct LossCurve {
    std::vector<double> step, loss;  // mean batch loss over each logging interval
};

NetworkWeights fitTransmissionNetwork(const RdmData& rdm, const FitConfig& config, uint64_t seed,
                                      tbb::task_arena& arena, bool quiet, LossCurve* curve);
// The colour-conditioned M network (yarn/colour_basis.h): 6 -> hidden -> 3K
// coefficients, trained as M but with a C_TT per channel drawn uniformly
// from the basis's range for every sample and its target computed for that
// colour from the recorded paths.
NetworkWeights fitColourConditionedMNetwork(const ColourTargets& targets,
                                            const ColourBasis& basis, const FitConfig& config,
                                            uint64_t seed, tbb::task_arena& arena, bool quiet,
                                            LossCurve* curve);
// One yarn of a family fit (family_fit.h): its parameters as network inputs
// (FamilyBox::normalised) and its gather's data on the family's bins.
struct FamilyTrainingPoint {
    std::array<float, FamilyBox::kDimensions> inputs{};
    std::vector<double> incidentCdf;   // cumulative path counts over incident bins
    std::vector<double> pT;            // P(T | incident bin)
    const ColourTargets* m = nullptr;  // its M records
    // The mean of its M targets over the training's cells (incident bins
    // uniform, outgoing in proportion to solid angle) per channel, at
    // kFamilyMeanNodes colours uniform over the fit's colour range: the
    // scale that the M loss divides each sample's residual by.
    std::array<std::vector<float>, 3> meanM;
};
inline constexpr int kFamilyMeanNodes = 64;

// The family's T network (kFamilyTInputs -> 1, sigmoid): as T above, with
// the yarn drawn uniformly for every sample and its N, rho, alpha as inputs
// after wi. `rmse` receives the kept restart's path-count-weighted RMS error
// over all yarns' incident bins.
NetworkWeights fitFamilyTransmissionNetwork(const std::vector<FamilyTrainingPoint>& points,
                                            const RdmBins& bins, const FitConfig& config,
                                            uint64_t seed, tbb::task_arena& arena, bool quiet,
                                            LossCurve* curve, double* rmse);
// The family's M network (kFamilyMInputs -> 3K): as the colour-conditioned M
// network, with the yarn drawn uniformly for every sample and its nine
// parameters as inputs after (wi, wo), and each sample's squared residual in
// channel c divided by the square of its yarn's mean M in c at its colour
// (FamilyTrainingPoint::meanM): the loss is relative per yarn and channel, as
// the error metric is, so that dark channels and dim yarns, whose noisy
// targets would otherwise weigh nothing against bright ones, are fitted too.
NetworkWeights fitFamilyMNetwork(const std::vector<FamilyTrainingPoint>& points,
                                 const ColourBasis& basis, const FitConfig& config, uint64_t seed,
                                 tbb::task_arena& arena, bool quiet, LossCurve* curve);

NetworkWeights fitMultipleScatteringNetwork(const RdmData& rdm, const FitConfig& config,
                                           uint64_t seed, tbb::task_arena& arena, bool quiet,
                                           LossCurve* curve);

}  // namespace weft
