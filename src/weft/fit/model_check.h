// weft/fit/model_check.h — checks a fitted yarn BSDF against a gathered RDM (weft yarn check).
//
// For every incident bin of the RDM, at the bin's centre direction wi:
//   model albedo  P(T|wi) + integral of (R + M)(wi, wo) dwo   (yarn_integrals.h),
//                 of the model as fitted (no energy guard; the guarded albedo,
//                 what the renderer uses, is summarised beside it)
//   RDM albedo    p_t + sum over outgoing bins o of (RDM_R + RDM_M)[i, o] * solid angle(o)
// and their relative difference per channel, summarised over the bins with at
// least `minPaths` paths (the RDM's own noise is about 1 / sqrt(paths)), and
// again after pooling both to the coarse incident grid of metrics.h;
// the coarse-grid relative L2 errors of R and M (metrics.h, the numbers of
// `weft fit`) and the path-count-weighted RMS error of P(T); and the variance
// proxies of the sampler (DirectionalIntegrals), averaged over incident bins.
//
// Report directory (written atomically):
//   check.json                summary (docs/yarn.md lists the keys)
//   albedo_model.npy          float64 (TI, PI, 3) model albedo at bin centres
//   albedo_rdm.npy            float64 (TI, PI, 3) RDM albedo
//   components_model.npy      float64 (TI, PI, 3, 3) the albedo's parts T, R, M (rows) per channel
//   components_rdm.npy        float64 (TI, PI, 3, 3) the same for the RDM (T = p_t in each
//                             channel)
//   sampling_weights.npy      float64 (TI, PI, 3) sample()'s weight w = eval / pdf on luminance,
//                             T included: E[w] / albedo, E[w^2] / E[w]^2, largest w / albedo
//   second_moment.npy         float64 (TI, PI, 3) relative second moments: yarn sampler,
//                             uniform sphere, cosine (DirectionalIntegrals)
//   albedo.png                RDM (left) and model (right) albedo: rows theta_i from 0 (top)
//                             to 90 degrees, columns phi_i from -180 to 180 degrees
//   slice-{m,r}-thetaTT-phiPPP.png  RDM (left) vs model (right) outgoing maps for a few wi
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "weft/gather/rdm_io.h"
#include "weft/yarn/yarn_model.h"

namespace weft {

struct YarnCheckOptions {
    int64_t minPaths = 1000;    // incident bins with fewer paths are left out of the albedo summary
    int threads = 0;            // 0: all cores; never changes the result
    bool dualBaseline = false;  // also check the dual-scattering baseline (below)
};

// The dual-scattering baseline (after ZMA23, yarn/dual_scattering.h) of the
// model's fiber and ply against the same RDM, with the neural model's metrics:
// its single-scattering part against the RDM's R (r_rel_l2), the rest against
// M (m_rel_l2), both against R + M (total_rel_l2, and the neural model's
// total beside it), and its directional albedo (quadrature at bin centres)
// against the RDM's p_t + R + M over the bins with at least `minPaths` paths.
// `neuralR`, `neuralM`: the neural model's maps (model_maps.h).
nlohmann::json checkDualBaseline(const YarnModel& model, const RdmData& rdm,
                                 const std::vector<float>& neuralR,
                                 const std::vector<float>& neuralM, int64_t minPaths);

// The computation: check.json's document and the arrays of the report.
struct YarnCheckResult {
    nlohmann::json summary;
    std::vector<double> albedoModel, albedoRdm;          // (TI, PI, 3)
    std::vector<double> componentsModel, componentsRdm;  // (TI, PI, 3, 3): T, R, M rows
    std::vector<double> secondMoments;                   // (TI, PI, 3)
    std::vector<double> samplingWeights;                 // (TI, PI, 3)
    std::vector<float> rMap, mMap;                       // the model's maps (model_maps.h)
};
YarnCheckResult computeYarnCheck(const YarnModel& model, const std::string& modelPath,
                                 const RdmData& rdm, const YarnCheckOptions& options);
// The writing: the report's files into the existing folder `dir`.
void writeYarnCheck(const YarnCheckResult& check, const RdmData& rdm, const std::string& dir);

// Both: writes the report to `outDir` (atomically: a temporary folder renamed
// into place) and returns check.json's document.
nlohmann::json checkYarnModel(const YarnModel& model, const std::string& modelPath,
                              const RdmData& rdm, const YarnCheckOptions& options,
                              const std::string& outDir);

}  // namespace weft
