#include "weft/core/chi2.h"

#include <algorithm>
#include <cmath>

#include "weft/core/math.h"

namespace weft {

double incompleteGammaQ(double a, double x) {
    if (x <= 0) return 1.0;
    const double logPrefactor = a * std::log(x) - x - std::lgamma(a);
    if (x < a + 1.0) {
        // Series for P(a, x).
        double term = 1.0 / a, sum = term;
        for (int n = 1; n < 10000; ++n) {
            term *= x / (a + n);
            sum += term;
            if (std::fabs(term) < std::fabs(sum) * 1e-16) break;
        }
        return std::max(0.0, 1.0 - sum * std::exp(logPrefactor));
    }
    // Continued fraction for Q(a, x) (modified Lentz).
    const double tiny = 1e-300;
    double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
    for (int n = 1; n < 10000; ++n) {
        const double an = -n * (n - a);
        b += 2.0;
        d = an * d + b;
        if (std::fabs(d) < tiny) d = tiny;
        c = b + an / c;
        if (std::fabs(c) < tiny) c = tiny;
        d = 1.0 / d;
        const double delta = d * c;
        h *= delta;
        if (std::fabs(delta - 1.0) < 1e-16) break;
    }
    return std::exp(logPrefactor) * h;
}

double chi2PValue(double chi2, int dof) { return incompleteGammaQ(0.5 * dof, 0.5 * chi2); }

double sidakCorrectedLevel(double alpha, int tests) {
    return 1.0 - std::pow(1.0 - alpha, 1.0 / tests);
}

Chi2Result chi2Test(const std::vector<double>& observed, const std::vector<double>& expected,
                    double minExpected) {
    std::vector<size_t> order(expected.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(),
              [&](size_t a, size_t b) { return expected[a] < expected[b]; });
    Chi2Result r;
    double pooledObserved = 0, pooledExpected = 0;
    int cells = 0;
    for (size_t i : order) {
        if (expected[i] <= 0) {
            // A sample where the pdf integrates to zero is an outright failure.
            if (observed[i] > 0) {
                r.statistic = INFINITY;
                r.pValue = 0;
                return r;
            }
            continue;
        }
        if (expected[i] < minExpected) {
            pooledObserved += observed[i];
            pooledExpected += expected[i];
            continue;
        }
        if (pooledExpected > 0 && pooledExpected < minExpected) {
            // Fold a too-small pool into the smallest regular cell.
            r.statistic += sqr(observed[i] + pooledObserved - expected[i] - pooledExpected) /
                           (expected[i] + pooledExpected);
            pooledObserved = pooledExpected = 0;
        } else {
            r.statistic += sqr(observed[i] - expected[i]) / expected[i];
        }
        ++cells;
    }
    if (pooledExpected > 0) {
        r.statistic += sqr(pooledObserved - pooledExpected) / pooledExpected;
        ++cells;
    }
    r.dof = std::max(1, cells - 1);
    r.pValue = chi2PValue(r.statistic, r.dof);
    return r;
}

namespace {

// Legendre polynomial P_n(x) and its derivative, by the three-term recurrence.
void legendre(int n, double x, double* p, double* dp) {
    double p0 = 1, p1 = x;
    for (int k = 2; k <= n; ++k) {
        const double p2 = ((2 * k - 1) * x * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    *p = p1;
    *dp = n * (x * p1 - p0) / (x * x - 1);
}

// Gauss-Legendre nodes and weights on [-1, 1]: Newton iteration on P_n from
// the Chebyshev-like initial guesses, w = 2 / ((1 - x^2) P_n'(x)^2).
void gaussLegendre(int n, std::vector<double>* nodes, std::vector<double>* weights) {
    nodes->resize(n);
    weights->resize(n);
    for (int k = 0; k < n; ++k) {
        double x = std::cos(kPi * (k + 0.75) / (n + 0.5)), p, dp;
        for (int it = 0; it < 100; ++it) {
            legendre(n, x, &p, &dp);
            const double dx = p / dp;
            x -= dx;
            if (std::fabs(dx) < 1e-15) break;
        }
        legendre(n, x, &p, &dp);
        (*nodes)[k] = x;
        (*weights)[k] = 2.0 / ((1 - x * x) * dp * dp);
    }
}

}  // namespace

int SphereGrid::cellOf(const Vec3& w) const {
    const double theta = std::atan2(w.x, std::sqrt(w.y * w.y + w.z * w.z));
    const double phi = std::atan2(w.z, w.y);
    const int i = std::clamp(static_cast<int>((theta + kHalfPi) / kPi * thetaBins), 0,
                             thetaBins - 1);
    const int j = std::clamp(static_cast<int>((phi + kPi) / kTwoPi * phiBins), 0, phiBins - 1);
    return i * phiBins + j;
}

std::vector<double> SphereGrid::expectedCounts(const std::function<double(const Vec3&)>& pdf,
                                               double sampleCount, int order) const {
    std::vector<double> nodes, weights;
    gaussLegendre(order, &nodes, &weights);
    const double dTheta = kPi / thetaBins, dPhi = kTwoPi / phiBins;
    std::vector<double> expected(cells(), 0.0);
    for (int i = 0; i < thetaBins; ++i) {
        for (int j = 0; j < phiBins; ++j) {
            double sum = 0;
            for (int a = 0; a < order; ++a) {
                const double theta = -kHalfPi + (i + 0.5 * (nodes[a] + 1)) * dTheta;
                const double cosTheta = std::cos(theta), sinTheta = std::sin(theta);
                for (int b = 0; b < order; ++b) {
                    const double phi = -kPi + (j + 0.5 * (nodes[b] + 1)) * dPhi;
                    const Vec3 w{sinTheta, cosTheta * std::cos(phi), cosTheta * std::sin(phi)};
                    sum += weights[a] * weights[b] * pdf(w) * cosTheta;
                }
            }
            expected[i * phiBins + j] = sum * 0.25 * dTheta * dPhi * sampleCount;
        }
    }
    return expected;
}

}  // namespace weft
