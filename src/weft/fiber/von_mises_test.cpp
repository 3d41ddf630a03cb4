#include "weft/fiber/von_mises.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "weft/core/chi2.h"
#include "weft/core/math.h"
#include "weft/core/test_util.h"

namespace weft {
namespace {

TEST(VonMises, MatchesTextbookFormulaAndIntegratesToOne) {
    for (double gammaDeg : {1.0, 19.823, 25.989, 38.269, 90.0}) {
        const double kappa = 1.0 / sqr(radians(gammaDeg));
        const VonMises vm(kappa);
        const int n = 200000;
        double sum = 0;
        for (int k = 0; k < n; ++k) sum += vm.pdf(-kPi + kTwoPi * (k + 0.5) / n);
        EXPECT_NEAR(sum * kTwoPi / n, 1.0, 1e-9) << gammaDeg;
        if (kappa < 600) {
            for (double x : {0.0, 0.4, -2.0, 3.0}) {
                const double textbook =
                    std::exp(kappa * std::cos(x)) / (kTwoPi * std::cyl_bessel_i(0.0, kappa));
                EXPECT_NEAR(vm.pdf(x) / textbook, 1.0, 1e-12);
            }
        }
    }
}

TEST(VonMises, SamplesFollowPdf) {
    const std::vector<double> gammas = {1.0, 10.0, 19.823, 38.269, 90.0};
    const double alpha = sidakCorrectedLevel(0.01, static_cast<int>(gammas.size()));
    for (double gammaDeg : gammas) {
        const double kappa = 1.0 / sqr(radians(gammaDeg));
        const VonMises vm(kappa);
        // Bins narrow enough to resolve the lobe.
        const double halfWidth = std::min(kPi, 6.0 * radians(gammaDeg));
        const int bins = 120;
        const int64_t n = testing::scaled(400000);
        std::vector<double> observed(bins + 1, 0), expected(bins + 1, 0);
        Rng rng(1, 2), rngU(9, 9);
        for (int64_t i = 0; i < n; ++i) {
            const double x = vm.sample(rngU.uniform(), rng);
            ASSERT_LE(std::fabs(x), kPi);
            const double s = (x + halfWidth) / (2 * halfWidth);
            observed[(s >= 0 && s < 1) ? static_cast<int>(s * bins) : bins] += 1;
        }
        double inside = 0;
        for (int b = 0; b < bins; ++b) {
            const double a = -halfWidth + 2 * halfWidth * b / bins;
            expected[b] = n * testing::simpson([&](double x) { return vm.pdf(x); }, a,
                                               a + 2 * halfWidth / bins, 200);
            inside += expected[b];
        }
        expected[bins] = std::max(0.0, n - inside);
        const Chi2Result r = chi2Test(observed, expected);
        EXPECT_GT(r.pValue, alpha) << "gamma = " << gammaDeg << ", chi2 = " << r.statistic;
    }
}

}  // namespace
}  // namespace weft
