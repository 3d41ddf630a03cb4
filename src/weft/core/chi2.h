// weft/core/chi2.h — chi-square goodness-of-fit of a direction sampler vs its pdf.
//
// As in pbrt-v4's and Mitsuba 3's test suites: sampled directions are binned on
// a (theta, phi) grid of the sphere, the expected count of every cell is the
// pdf integrated over the cell (Gauss-Legendre quadrature), cells with small
// expectations are pooled, and Pearson's statistic gives a p-value through the
// regularised incomplete gamma function. Grid directions use the fiber
// convention: w = (sin theta, cos theta cos phi, cos theta sin phi), theta in
// [-pi/2, pi/2], phi in [-pi, pi).
#pragma once

#include <functional>
#include <vector>

#include "weft/core/vec.h"

namespace weft {

// Upper regularised incomplete gamma Q(a, x) = Gamma(a, x) / Gamma(a).
double incompleteGammaQ(double a, double x);

// P(X >= chi2) for X chi-square distributed with `dof` degrees of freedom.
double chi2PValue(double chi2, int dof);

// Per-test significance so that `tests` independent tests have overall level alpha (Sidak).
double sidakCorrectedLevel(double alpha, int tests);

struct Chi2Result {
    double statistic = 0;
    int dof = 0;
    double pValue = 1;
};

// Pearson's test; cells whose expected count is below minExpected are pooled
// into one cell (pbrt-v4 style).
Chi2Result chi2Test(const std::vector<double>& observed, const std::vector<double>& expected,
                    double minExpected = 5.0);

struct SphereGrid {
    int thetaBins, phiBins;

    int cells() const { return thetaBins * phiBins; }
    int cellOf(const Vec3& w) const;
    // The integral of pdf over every cell, times sampleCount.
    std::vector<double> expectedCounts(const std::function<double(const Vec3&)>& pdf,
                                       double sampleCount, int quadratureOrder = 8) const;
};

}  // namespace weft
