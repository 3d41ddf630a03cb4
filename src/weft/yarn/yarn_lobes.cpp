#include "weft/yarn/yarn_lobes.h"

#include <algorithm>
#include <cmath>

#include "weft/core/error.h"
#include "weft/core/math.h"
#include "weft/core/sampling.h"

namespace weft {

SurfaceFiberFrame SurfaceFiberFrame::fromTiltDeg(double tiltDeg) {
    return {std::cos(radians(tiltDeg)), std::sin(radians(tiltDeg))};
}

double SurfaceFiberFrame::tiltDegOfTwist(double twist) { return degrees(std::atan(kPi * twist)); }

std::array<double, kMaskingCoefficients> maskingBasis(double muI, double muO) {
    return {1.0, muI + muO, muI * muO, muI * muI + muO * muO};
}

namespace {

template <typename Params>
const Params& validated(const Params& p) {
    p.validate();
    return p;
}

}  // namespace

RLobe::RLobe(const FiberParams& fiber, const RLobeParams& params)
    : params_(validated(params)),
      frame_(SurfaceFiberFrame::fromTiltDeg(params.tiltDeg)),
      fiber_(fiber) {}

double RLobe::masking(const Vec3& wi, const Vec3& wo) const {
    if (params_.masking.empty()) return 1.0;
    const auto basis = maskingBasis(wi.z, wo.z);
    double m = 0;
    for (int k = 0; k < kMaskingCoefficients; ++k) m += params_.masking[k] * basis[k];
    return std::clamp(m, 0.0, 1.0);
}

Rgb RLobe::evalFiber(const Vec3& wi, const Vec3& wo) const {
    if (wi.z <= 0 || wo.z <= 0) return Rgb(0.0);
    return fiber_.eval(frame_.toLocal(wi), frame_.toLocal(wo));
}

Rgb RLobe::eval(const Vec3& wi, const Vec3& wo, double pT) const {
    if (wi.z <= 0 || wo.z <= 0) return Rgb(0.0);
    return evalFiber(wi, wo) * ((1.0 - pT) * masking(wi, wo));
}

Rgb RLobe::eval(const Vec3& wi, const Vec3& wo, const FiberBcsdf::Incident& fiberIn,
                const FiberBcsdf::Angles& out, double pT) const {
    if (wi.z <= 0 || wo.z <= 0) return Rgb(0.0);
    return fiber_.evalPrepared(fiberIn, out) * ((1.0 - pT) * masking(wi, wo));
}

TruncatedGaussian::TruncatedGaussian(double beta) : beta_(beta) {
    if (!(beta > 0 && beta <= kPi)) throw InputError("truncated Gaussian width out of range (0, pi]");
}

namespace {

// erf of the standardised bounds of [-pi/2, pi/2] around mu.
struct Bounds {
    double lo, hi;
};
Bounds erfBounds(double mu, double beta) {
    const double s = 1.0 / (beta * std::sqrt(2.0));
    return {std::erf((-kPi / 2 - mu) * s), std::erf((kPi / 2 - mu) * s)};
}

}  // namespace

double TruncatedGaussian::inverseMass(double mu) const {
    const Bounds b = erfBounds(mu, beta_);
    return 2.0 / (b.hi - b.lo);
}

double TruncatedGaussian::pdf(double theta, double mu, double inverseMass) const {
    if (theta < -kPi / 2 || theta > kPi / 2) return 0.0;
    const double x = (theta - mu) / beta_;
    return std::exp(-0.5 * x * x) * inverseMass / (beta_ * std::sqrt(2.0 * kPi));
}

double TruncatedGaussian::pdf(double theta, double mu) const {
    return pdf(theta, mu, inverseMass(mu));
}

double TruncatedGaussian::sample(double mu, double u) const {
    const Bounds b = erfBounds(mu, beta_);
    const double theta = mu + beta_ * std::sqrt(2.0) * erfInv(b.lo + u * (b.hi - b.lo));
    return std::clamp(theta, -kPi / 2, kPi / 2);
}

SamplingLobes::SamplingLobes(const FiberParams& fiber, double tiltDeg, const SamplingParams& params)
    : params_(validated(params)),
      frame_(SurfaceFiberFrame::fromTiltDeg(tiltDeg)),
      gR_(radians(fiber.betaRDeg)),
      gM_(radians(params.betaMDeg)),
      vonMisesM_(1.0 / (radians(params.gammaMDeg) * radians(params.gammaMDeg))) {}

double SamplingLobes::pdfR(const Vec3& wi, const Vec3& wo) const {
    if (wo.z <= 0) return 0.0;  // the upper half cone |phi_o| < pi/2
    const double thetaI = frame_.longitudinalAngle(wi);
    const SurfaceFiberFrame::Angles out = frame_.angles(wo);
    if (out.cosTheta <= 0) return 0.0;
    return gR_.pdf(out.theta, -thetaI) / (kPi * out.cosTheta);
}

double SamplingLobes::pdfM(double thetaI, double inverseMass, const Angles& out,
                           double vonMisesDensity) const {
    const double uniform = (1.0 - params_.kappaM) / (4.0 * kPi);
    if (out.cosTheta <= 0 || params_.kappaM == 0) return uniform;
    return params_.kappaM * gM_.pdf(out.theta, -thetaI, inverseMass) * vonMisesDensity /
               out.cosTheta +
           uniform;
}

Vec3 SamplingLobes::sampleR(const Vec3& wi, double u1, double u2) const {
    const double thetaO = gR_.sample(-frame_.longitudinalAngle(wi), u1);
    return frame_.direction(thetaO, kPi * (u2 - 0.5));
}

Vec3 SamplingLobes::sampleM(const Vec3& wi, double uLobe, double u1, double u2, Rng& rng) const {
    if (uLobe < params_.kappaM) {
        const double thetaO = gM_.sample(-frame_.longitudinalAngle(wi), u1);
        return frame_.direction(thetaO, vonMisesM_.sample(u2, rng));
    }
    return sampleUniformSphere(u1, u2);  // in any frame
}

double SamplingLobes::pdfM(const Vec3& wi, const Vec3& wo) const {
    const double thetaI = frame_.longitudinalAngle(wi);
    const Angles out = anglesOf(wo);
    return pdfM(thetaI, gM_.inverseMass(-thetaI), out, vonMisesM_.pdfOfCos(out.cosPhi));
}

}  // namespace weft
