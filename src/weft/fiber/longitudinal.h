// weft/fiber/longitudinal.h — the longitudinal Gaussian of the fiber model.
//
// g(theta; mu, beta) is a Gaussian in the longitudinal angle theta, normalised
// on [-pi/2, pi/2] against the cos^2 measure (docs/design.md 3, paper eq. 3,
// Khungurn et al. 2015):
//     integral_{-pi/2}^{pi/2} g(theta; mu, beta) cos^2(theta) dtheta = 1.
// The normaliser Z(mu) = integral exp(-(theta-mu)^2 / (2 beta^2)) cos^2 dtheta
// has no real closed form, so it is tabulated once per width beta: log Z and
// its derivative at 2049 nodes over |mu| in [0, pi/2], each computed by
// composite 8-point Gauss-Legendre quadrature to about 1e-14, and
// interpolated with cubic Hermite splines (relative error < 1e-8 for beta of
// 1 degree, smaller for wider lobes).
//
// Sampling draws theta from the density g cos^2 on [-pi/2, pi/2] exactly, by
// rejection. Proposals come from a Gaussian of width beta centred on c (the
// target's mode, tabulated), truncated to [-pi/2, pi/2] (inverse CDF with
// erf / erfInv). Target / proposal is proportional to cos^2(t) exp(s (t - c))
// with s = (mu - c) / beta^2; log cos^2 is concave, so its tangent at
// t* = atan(s / 2) bounds it, and a proposal is accepted with probability
// cos^2(t) exp(s (t - t*)) / cos^2(t*) <= 1. The sampled density is the target
// itself for any c, not an approximation; c at the mode keeps the acceptance
// rate around 0.5 or more for every mu and beta in (0, pi/2].
#pragma once

#include <cstddef>
#include <vector>

#include "weft/core/rng.h"

namespace weft {

class LongitudinalGaussian {
public:
    // beta: standard deviation in radians, in (0, pi/2].
    explicit LongitudinalGaussian(double beta);

    double beta() const { return beta_; }
    // Bytes of the object and its tables.
    size_t memoryBytes() const {
        return sizeof(*this) + (logZ_.size() + dLogZ_.size() + mode_.size()) * sizeof(double);
    }

    // Z(mu), the normaliser; symmetric in mu.
    double normalization(double mu) const;
    double logNormalization(double mu) const;
    // The proposal centre of sample(): the mode of g cos^2, interpolated from a
    // table (sample() is exact for any centre; the mode keeps it efficient).
    double proposalCentre(double mu) const;

    // g(theta; mu, beta) = exp(-(theta - mu)^2 / (2 beta^2)) / Z(mu).
    double eval(double theta, double mu) const;

    // theta distributed with density g(theta; mu, beta) cos^2(theta) on
    // [-pi/2, pi/2]. u drives the first proposal; rng supplies the rest.
    double sample(double mu, double u, Rng& rng) const;

    // Z(mu) by direct quadrature (the reference the table is built from).
    double normalizationByQuadrature(double mu, double* derivative = nullptr) const;

private:
    double beta_, inv2Beta2_;
    double nodeSpacing_;
    std::vector<double> logZ_, dLogZ_;  // at mu = j * nodeSpacing_, j = 0..n
    std::vector<double> mode_;          // mode of g cos^2 at the same nodes
};

}  // namespace weft
