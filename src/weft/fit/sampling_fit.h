// weft/fit/sampling_fit.h — step 5 of the fit: the M sampling lobe
// (paper eq. 10, yarn/yarn_lobes.h).
#pragma once

#include <vector>

#include "weft/gather/rdm.h"
#include "weft/yarn/yarn_model.h"

namespace weft {

// Step 5: beta_M, gamma_M, kappa_M minimising the mean over incident
// directions of sum_o f^2 / pdf_M dw / (sum_o f dw)^2 (f: the channel mean of
// mMap; 1 when pdf_M is proportional to f), for the model's fiber and tilt.
// kappaR is copied into the result; `secondMoment` receives the minimum.
SamplingParams fitSamplingLobe(const YarnModel& model, const std::vector<float>& mMap,
                               const RdmBins& bins, double kappaR, double* secondMoment = nullptr,
                               int threads = 0);

}  // namespace weft
