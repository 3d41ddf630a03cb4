#include "weft/fiber/von_mises.h"

#include <cmath>

#include "weft/core/math.h"

namespace weft {

namespace {

// Best & Fisher: tau = 1 + sqrt(1 + 4 k^2), rho = (tau - sqrt(2 tau)) / (2k),
// r = (1 + rho^2) / (2 rho). We carry r - 1 = (1 - rho)^2 / (2 rho) and
// 1 - rho (from 2k - tau = -1 - 1 / (sqrt(1 + 4k^2) + 2k)) instead, so that
// nothing cancels when kappa is large.
double bestFisherRMinus1(double kappa) {
    const double root = std::sqrt(1.0 + 4.0 * kappa * kappa);
    const double tau = 1.0 + root;
    const double oneMinusRho =
        (std::sqrt(2.0 * tau) - 1.0 - 1.0 / (root + 2.0 * kappa)) / (2.0 * kappa);
    const double rho = 1.0 - oneMinusRho;
    return oneMinusRho * oneMinusRho / (2.0 * rho);
}

double sampleBestFisher(double kappa, double rMinus1, double u, Rng& rng) {
    for (int round = 0; round < 200; ++round) {
        const double u1 = round == 0 ? u : rng.uniform();
        // z = cos(pi u1); 1 + z and 1 - z without cancellation.
        const double onePlusZ = 2.0 * sqr(std::cos(0.5 * kPi * u1));
        const double oneMinusZ = 2.0 * sqr(std::sin(0.5 * kPi * u1));
        const double rPlusZ = rMinus1 + onePlusZ;
        if (!(rPlusZ > 0)) continue;
        // f = (1 + r z) / (r + z); c = kappa (r - f); 1 - f = (r - 1)(1 - z) / (r + z).
        const double c = kappa * rMinus1 * (rMinus1 + 2.0) / rPlusZ;
        const double oneMinusF = rMinus1 * oneMinusZ / rPlusZ;
        const double u2 = rng.uniform();
        if (c * (2.0 - c) - u2 > 0 || std::log(c / u2) + 1.0 - c >= 0) {
            const double angle = 2.0 * safeAsin(std::sqrt(0.5 * oneMinusF));
            return rng.uniform() < 0.5 ? -angle : angle;
        }
    }
    return 0.0;
}

}  // namespace

VonMises::VonMises(double kappa)
    : kappa_(kappa),
      invNorm_(1.0 / (kTwoPi * besselI0Scaled(kappa))),
      rMinus1_(bestFisherRMinus1(kappa)) {}

double VonMises::pdf(double x) const { return pdfOfCos(std::cos(x)); }

double VonMises::pdfOfCos(double cosX) const {
    return std::exp(kappa_ * (cosX - 1.0)) * invNorm_;
}

double VonMises::sample(double u, Rng& rng) const {
    return sampleBestFisher(kappa_, rMinus1_, u, rng);
}


}  // namespace weft
