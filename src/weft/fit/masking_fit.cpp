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
    Eigen::Matrix4d a = Eigen::Matrix4d::Zero();
    Eigen::Vector4d b = Eigen::Vector4d::Zero();
    forEachMaskingRow(pe, pr, coarse, [&](double w, const auto& basis, double e, double r) {
        Eigen::Vector4d v;
        for (int j = 0; j < kMaskingCoefficients; ++j) v[j] = basis[j] * e;
        a += w * v * v.transpose();
        b += w * v * r;
    });
    const Eigen::Vector4d c = a.ldlt().solve(b);
    return {c[0], c[1], c[2], c[3]};
}

}  // namespace weft
