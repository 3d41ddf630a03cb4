#include "weft/fiber/longitudinal.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "weft/core/chi2.h"
#include "weft/core/math.h"
#include "weft/core/test_util.h"

namespace weft {
namespace {

// Independent reference: composite Simpson over [-pi/2, pi/2] with a step far
// below the narrowest width (1 degree), no tables, no Gauss-Legendre.
double simpsonCos2Integral(const LongitudinalGaussian& g, double mu) {
    return testing::simpson([&](double t) { return g.eval(t, mu) * sqr(std::cos(t)); }, -kHalfPi,
                            kHalfPi, 200000);
}

const std::vector<double> kWidthsDeg = {1.0, 2.141, 5.238, 7.238, 10.0, 20.0, 27.197, 45.0, 90.0};
const std::vector<double> kMeansRad = {0.0,   0.3,  -0.7,          1.2,          -1.5,
                                       1.55,  1.57, kHalfPi - 1e-9, -kHalfPi,     kHalfPi};

TEST(LongitudinalGaussian, NormalisedAgainstCos2ForEveryMeanAndWidth) {
    for (double deg : kWidthsDeg) {
        const LongitudinalGaussian g(radians(deg));
        for (double mu : kMeansRad) {
            EXPECT_NEAR(simpsonCos2Integral(g, mu), 1.0, 1e-7)
                << "beta = " << deg << " deg, mu = " << mu;
        }
    }
}

TEST(LongitudinalGaussian, TableMatchesQuadratureBetweenNodes) {
    for (double deg : {1.0, 7.238, 27.197}) {
        const LongitudinalGaussian g(radians(deg));
        for (int k = 0; k < 997; ++k) {
            const double mu = -kHalfPi + kPi * (k + 0.37) / 997.0;
            const double exact = g.normalizationByQuadrature(mu);
            EXPECT_NEAR(g.normalization(mu) / exact, 1.0, 1e-8) << deg << " " << mu;
        }
    }
}

TEST(LongitudinalGaussian, SamplesFollowGCos2) {
    const double alpha = sidakCorrectedLevel(0.01, static_cast<int>(4 * 5));
    for (double deg : {1.0, 10.0, 27.197, 90.0}) {
        const LongitudinalGaussian g(radians(deg));
        for (double mu : {0.0, 0.8, -1.3, kHalfPi - 0.01, kHalfPi}) {
            const int bins = 200;
            const int64_t n = testing::scaled(400000);
            std::vector<double> observed(bins, 0), expected(bins, 0);
            Rng rng(7, 11), rngU(3, 5);
            for (int64_t i = 0; i < n; ++i) {
                const double t = g.sample(mu, rngU.uniform(), rng);
                ASSERT_GE(t, -kHalfPi);
                ASSERT_LE(t, kHalfPi);
                observed[std::min(bins - 1, static_cast<int>((t + kHalfPi) / kPi * bins))] += 1;
            }
            // Expected counts by Simpson integration of g cos^2 over each bin.
            for (int b = 0; b < bins; ++b) {
                const double a = -kHalfPi + kPi * b / bins;
                expected[b] = n * testing::simpson(
                                      [&](double t) { return g.eval(t, mu) * sqr(std::cos(t)); }, a,
                                      a + kPi / bins, 400);
            }
            const Chi2Result r = chi2Test(observed, expected);
            EXPECT_GT(r.pValue, alpha) << "beta = " << deg << " deg, mu = " << mu
                                       << ", chi2 = " << r.statistic << ", dof = " << r.dof;
        }
    }
}

}  // namespace
}  // namespace weft
