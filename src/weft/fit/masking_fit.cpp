// The R lobe's masking term (masking_fit.h): linear least squares on the coarse grid.
#include "weft/fit/masking_fit.h"

#include <Eigen/Dense>

#include "weft/fit/metrics.h"
#include "weft/yarn/yarn_lobes.h"

namespace weft {

// Least-squares masking coefficients: minimise
// sum W_O (m(mu_I, mu_O) P_eq8 - P_rdm)^2 over the coarse grid and channels.
std::vector<double> fitMaskingCoefficients(const std::vector<float>& eq8,
                                           const std::vector<float>& rdmR, const RdmBins& fine) {
    const RdmBins& coarse = kCoarseErrorBins;
    const std::vector<double> pe = poolRdm(eq8, fine, coarse), pr = poolRdm(rdmR, fine, coarse);
    const size_t cIn = coarse.incidentCount(), cOut = coarse.outgoingCount();
    Eigen::Matrix4d a = Eigen::Matrix4d::Zero();
    Eigen::Vector4d b = Eigen::Vector4d::Zero();
    for (size_t I = 0; I < cIn; ++I) {
        const double muI = coarse.incidentCentre(I).z;
        for (size_t O = 0; O < cOut; ++O) {
            const double muO = coarse.outgoingCentre(O).z;
            if (muO <= 0) continue;
            const double w = coarse.outgoingSolidAngle(O);
            const auto basis = maskingBasis(muI, muO);
            for (int c = 0; c < 3; ++c) {
                const size_t k = (I * cOut + O) * 3 + c;
                Eigen::Vector4d v;
                for (int j = 0; j < kMaskingCoefficients; ++j) v[j] = basis[j] * pe[k];
                a += w * v * v.transpose();
                b += w * v * pr[k];
            }
        }
    }
    const Eigen::Vector4d c = a.ldlt().solve(b);
    return {c[0], c[1], c[2], c[3]};
}

}  // namespace weft
