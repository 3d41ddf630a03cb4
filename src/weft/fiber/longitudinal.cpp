#include "weft/fiber/longitudinal.h"

#include <algorithm>
#include <cmath>

#include "weft/core/math.h"
#include "weft/core/quadrature.h"

namespace weft {

namespace {

constexpr int kTableIntervals = 2048;

// Mode of exp(-(t - mu)^2 / (2 beta^2)) cos^2 t, i.e. the root of
// t - mu + 2 beta^2 tan t = 0, which lies between 0 and mu. By symmetry take
// mu >= 0 and write t = pi/2 - u, v = pi/2 - mu: the root solves
//     H(u) = (u - v) sin u - 2 beta^2 cos u = 0,  u in [v, pi/2],
// where H is smooth and increasing (no pole at the fiber tangent). The small-
// angle root u0 = (v + sqrt(v^2 + 8 beta^2)) / 2 starts safeguarded Newton.
// sample() stays exact for any proposal centre; the mode keeps it efficient.
double targetMode(double mu, double beta) {
    const double b2 = 2.0 * beta * beta;
    const double v = kHalfPi - std::fabs(mu);
    double lo = v, hi = kHalfPi;
    double u = std::clamp(0.5 * (v + std::sqrt(v * v + 4.0 * b2)), lo, hi);
    for (int i = 0; i < 8; ++i) {
        const double su = std::sin(u), cu = std::cos(u);
        const double h = (u - v) * su - b2 * cu;
        if (h > 0) hi = u; else lo = u;
        const double dh = (1.0 + b2) * su + (u - v) * cu;
        double next = u - h / dh;
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        const bool converged = std::fabs(next - u) < 1e-12;
        u = next;
        if (converged) break;
    }
    return std::copysign(kHalfPi - u, mu);
}

}  // namespace

LongitudinalGaussian::LongitudinalGaussian(double beta)
    : beta_(beta), inv2Beta2_(0.5 / (beta * beta)), nodeSpacing_(kHalfPi / kTableIntervals) {
    logZ_.resize(kTableIntervals + 1);
    dLogZ_.resize(kTableIntervals + 1);
    mode_.resize(kTableIntervals + 1);
    for (int j = 0; j <= kTableIntervals; ++j) {
        mode_[j] = targetMode(j * nodeSpacing_, beta_);
        double dz = 0;
        const double z = normalizationByQuadrature(j * nodeSpacing_, &dz);
        logZ_[j] = std::log(z);
        dLogZ_[j] = dz / z;
    }
}

double LongitudinalGaussian::normalizationByQuadrature(double mu, double* derivative) const {
    // The integrand is negligible (< exp(-60)) beyond 11 beta from mu.
    const double a = std::max(-kHalfPi, mu - 11.0 * beta_);
    const double b = std::min(kHalfPi, mu + 11.0 * beta_);
    const int panels = std::max(8, static_cast<int>(std::ceil((b - a) / (0.5 * beta_))));
    const double width = (b - a) / panels;
    const double inv2b2 = 1.0 / (2.0 * beta_ * beta_);
    double z = 0, dz = 0;
    for (int p = 0; p < panels; ++p) {
        const double centre = a + (p + 0.5) * width;
        // The 8-point Gauss-Legendre rule: the negative nodes, then the positive ones.
        for (int k = 0; k < 8; ++k) {
            const double x = (k < 4 ? -1.0 : 1.0) * quadrature::kGaussLegendre8HalfNodes[k % 4];
            const double t = centre + 0.5 * width * x;
            const double w = quadrature::kGaussLegendre8HalfWeights[k % 4] * 0.5 * width;
            const double c = std::cos(t);
            const double v = w * std::exp(-sqr(t - mu) * inv2b2) * c * c;
            z += v;
            dz += v * (t - mu) / (beta_ * beta_);
        }
    }
    if (derivative) *derivative = dz;
    return z;
}

double LongitudinalGaussian::logNormalization(double mu) const {
    // Z is even in mu; interpolate log Z on |mu| with cubic Hermite splines.
    const double x = std::min(std::fabs(mu), kHalfPi) / nodeSpacing_;
    const int j = std::min(static_cast<int>(x), kTableIntervals - 1);
    const double s = x - j, s2 = s * s, s3 = s2 * s;
    const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s;
    const double h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
    return h00 * logZ_[j] + h10 * nodeSpacing_ * dLogZ_[j] + h01 * logZ_[j + 1] +
           h11 * nodeSpacing_ * dLogZ_[j + 1];
}

double LongitudinalGaussian::proposalCentre(double mu) const {
    const double x = std::min(std::fabs(mu), kHalfPi) / nodeSpacing_;
    const int j = std::min(static_cast<int>(x), kTableIntervals - 1);
    const double s = x - j;
    return std::copysign((1.0 - s) * mode_[j] + s * mode_[j + 1], mu);
}

double LongitudinalGaussian::normalization(double mu) const {
    return std::exp(logNormalization(mu));
}

double LongitudinalGaussian::eval(double theta, double mu) const {
    return std::exp(-sqr(theta - mu) * inv2Beta2_ - logNormalization(mu));
}

double LongitudinalGaussian::sample(double mu, double u, Rng& rng) const {
    // Proposal: Gaussian of width beta centred on c (about the target's mode),
    // truncated to [-pi/2, pi/2]. Target / proposal is proportional to
    // cos^2(t) exp(s (t - c)) with s = (mu - c) / beta^2. log cos^2 is concave
    // with slope -2 tan t, so its tangent at t* = atan(s / 2) bounds it:
    // cos^2(t) exp(s t) <= cos^2(t*) exp(s t*). Accepting with the ratio of the
    // two sides gives exactly g cos^2 for any c.
    const double centre = proposalCentre(mu);
    const double slope = (mu - centre) / (beta_ * beta_);
    const double tangentPoint = std::atan(0.5 * slope);
    // 1 / cos^2(t*) = 1 + tan^2(t*) = 1 + s^2 / 4.
    const double invCos2Tangent = 1.0 + 0.25 * slope * slope;
    const double scale = std::sqrt(2.0) * beta_;
    // erf is exactly +-1 in double beyond 6, so skip it there.
    const double lo = (-kHalfPi - centre) / scale, hi = (kHalfPi - centre) / scale;
    const double erfLo = lo < -6.0 ? -1.0 : std::erf(lo);
    const double erfHi = hi > 6.0 ? 1.0 : std::erf(hi);
    // The acceptance rate is above 0.45, so 200 rounds fail with probability
    // below 1e-50; the cap only guarantees termination.
    for (int round = 0; round < 200; ++round) {
        const double uProposal = round == 0 ? u : rng.uniform();
        const double y = erfLo + uProposal * (erfHi - erfLo);
        const double theta = std::clamp(centre + scale * erfInv(y), -kHalfPi, kHalfPi);
        const double c = std::cos(theta);
        if (c <= 0) continue;
        const double accept = c * c * invCos2Tangent * std::exp(slope * (theta - tangentPoint));
        if (rng.uniform() < accept) return theta;
    }
    return centre;
}

}  // namespace weft
