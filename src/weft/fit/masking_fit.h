// weft/fit/masking_fit.h — step 2 of the fit: the R lobe's masking term
// (yarn/yarn_lobes.h, maskingBasis).
#pragma once

#include <vector>

#include "weft/gather/rdm.h"

namespace weft {

// Step 2: least-squares masking coefficients (yarn_lobes.h) so that
// m(wi, wo) * eq8 matches rdmR on the coarse error grid (both maps on `bins`).
std::vector<double> fitMaskingCoefficients(const std::vector<float>& eq8,
                                           const std::vector<float>& rdmR, const RdmBins& bins);

}  // namespace weft
