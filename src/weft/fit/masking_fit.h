// weft/fit/masking_fit.h — step 2 of the fit: the R lobe's masking term
// (yarn/yarn_lobes.h, maskingBasis).
#pragma once

#include <vector>

#include "weft/gather/rdm.h"
#include "weft/yarn/yarn_lobes.h"

namespace weft {

// The rows of the masking least squares on the coarse error grid
// (fit/metrics.h): row(w, basis, eq8, rdm) for every cell whose outgoing
// direction is above the surface and every channel, w the cell's solid
// angle, basis = maskingBasis(mu_I, mu_O), eq8 and rdm the pooled maps' values.
template <typename Row>
void forEachMaskingRow(const std::vector<double>& eq8, const std::vector<double>& rdm,
                       const RdmBins& coarse, Row&& row) {
    const size_t cIn = coarse.incidentCount(), cOut = coarse.outgoingCount();
    for (size_t I = 0; I < cIn; ++I) {
        const double muI = coarse.incidentCentre(I).z;
        for (size_t O = 0; O < cOut; ++O) {
            const double muO = coarse.outgoingCentre(O).z;
            if (muO <= 0) continue;
            const double w = coarse.outgoingSolidAngle(O);
            const auto basis = maskingBasis(muI, muO);
            for (int c = 0; c < 3; ++c) {
                const size_t k = (I * cOut + O) * 3 + c;
                row(w, basis, eq8[k], rdm[k]);
            }
        }
    }
}

// Step 2: least-squares masking coefficients (yarn_lobes.h) so that
// m(wi, wo) * eq8 matches rdmR on the coarse error grid (both maps on `bins`).
std::vector<double> fitMaskingCoefficients(const std::vector<float>& eq8,
                                           const std::vector<float>& rdmR, const RdmBins& bins);

}  // namespace weft
