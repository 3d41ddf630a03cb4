#include "weft/fiber/fiber_bcsdf.h"

#include <cmath>

#include "weft/core/math.h"

namespace weft {

namespace {

const FiberParams& validated(const FiberParams& p) {
    p.validate();
    return p;
}

}  // namespace

FiberBcsdf::FiberBcsdf(const FiberParams& params)
    : params_(validated(params)),
      gR_(radians(params.betaRDeg)),
      gTT_(radians(params.betaTTDeg)),
      nTT_(1.0 / sqr(radians(params.gammaTTDeg))) {}

FiberBcsdf::Angles FiberBcsdf::anglesOf(const Vec3& w) {
    Angles a;
    // cos theta from the y-z components keeps full precision near the tangent.
    a.cosTheta = std::sqrt(w.y * w.y + w.z * w.z);
    a.sinTheta = w.x;
    a.theta = std::atan2(w.x, a.cosTheta);
    a.y = w.y;
    a.z = w.z;
    return a;
}

Rgb FiberBcsdf::fresnel(double cosTheta) const {
    const double m = 1.0 - std::clamp(cosTheta, 0.0, 1.0);
    const double k = (m * m) * (m * m) * m;
    return params_.cR + (Rgb(1.0) - params_.cR) * k;
}

Rgb FiberBcsdf::albedo(const Vec3& wi) const {
    const Rgb f = fresnel(anglesOf(wi).cosTheta);
    return f + (Rgb(1.0) - f) * params_.cTT;
}

double FiberBcsdf::probabilityR(const Rgb& f) const {
    const double energyR = f.average();
    const double energyTT = ((Rgb(1.0) - f) * params_.cTT).average();
    const double total = energyR + energyTT;
    return total > 0 ? energyR / total : 0.5;
}

void FiberBcsdf::evalAndPdf(const Angles& in, const Angles& out, Rgb* value,
                            double* density) const {
    if (out.cosTheta <= 0) {
        if (value) *value = Rgb();
        if (density) *density = 0;
        return;
    }
    const Rgb f = fresnel(in.cosTheta);
    const double gR = gR_.eval(out.theta, -in.theta);
    const double gTT = gTT_.eval(out.theta, -in.theta);
    const double nR = 1.0 / kTwoPi;
    // cos(phi_o - phi_i - pi) = -cos(phi_o - phi_i); for wi along the fiber
    // phi_i is undefined and taken as 0 (the +y axis).
    double cosDeltaPhi;
    if (in.cosTheta > 0) {
        cosDeltaPhi = -(in.y * out.y + in.z * out.z) / (in.cosTheta * out.cosTheta);
    } else {
        cosDeltaPhi = -out.y / out.cosTheta;
    }
    const double nTT = nTT_.pdfOfCos(std::clamp(cosDeltaPhi, -1.0, 1.0));
    // eval = S_f cos(theta_o) (DESIGN.md 3).
    if (value) *value = (f * (gR * nR) + params_.cTT * (Rgb(1.0) - f) * (gTT * nTT)) * out.cosTheta;
    if (density) {
        // (theta, phi) density p_R gR cos^2 nR + p_TT gTT cos^2 nTT, over cos(theta_o).
        const double pR = probabilityR(f);
        *density = (pR * gR * nR + (1.0 - pR) * gTT * nTT) * out.cosTheta;
    }
}

Rgb FiberBcsdf::eval(const Vec3& wi, const Vec3& wo) const {
    Rgb value;
    evalAndPdf(anglesOf(wi), anglesOf(wo), &value, nullptr);
    return value;
}

double FiberBcsdf::pdf(const Vec3& wi, const Vec3& wo) const {
    double density;
    evalAndPdf(anglesOf(wi), anglesOf(wo), nullptr, &density);
    return density;
}

BsdfSample FiberBcsdf::sample(const Vec3& wi, const BsdfSampleInput& u) const {
    // Rejection steps draw from a generator seeded by the input numbers, so the
    // result is a deterministic function of (wi, u).
    Rng rng(hashDouble(u[0]) ^ (hashDouble(u[1]) >> 1), hashDouble(u[2]));
    return sample(wi, u, rng);
}

BsdfSample FiberBcsdf::sample(const Vec3& wi, const BsdfSampleInput& u, Rng& rng) const {
    const Angles in = anglesOf(wi);
    const double pR = probabilityR(fresnel(in.cosTheta));
    BsdfSample s;
    s.lobe = u[0] < pR ? kLobeR : kLobeTT;
    const LongitudinalGaussian& g = s.lobe == kLobeR ? gR_ : gTT_;
    const double thetaO = g.sample(-in.theta, u[1], rng);
    // Azimuth as a unit vector (cos phi_o, sin phi_o) in the y-z plane.
    double cosPhiO, sinPhiO;
    if (s.lobe == kLobeR) {
        const double phi = kTwoPi * u[2] - kPi;
        cosPhiO = std::cos(phi);
        sinPhiO = std::sin(phi);
    } else {
        // phi_o = phi_i + pi + delta: rotate the reversed azimuth of wi by delta.
        const double cosPhiI = in.cosTheta > 0 ? in.y / in.cosTheta : 1.0;
        const double sinPhiI = in.cosTheta > 0 ? in.z / in.cosTheta : 0.0;
        const double delta = nTT_.sample(u[2], rng);
        const double cd = std::cos(delta), sd = std::sin(delta);
        cosPhiO = -(cosPhiI * cd - sinPhiI * sd);
        sinPhiO = -(sinPhiI * cd + cosPhiI * sd);
    }
    const double cosThetaO = std::cos(thetaO), sinThetaO = std::sin(thetaO);
    s.wo = {sinThetaO, cosThetaO * cosPhiO, cosThetaO * sinPhiO};
    // The angles of wo are known: no need for anglesOf(s.wo).
    const Angles out{sinThetaO, cosThetaO, thetaO, s.wo.y, s.wo.z};
    Rgb value;
    evalAndPdf(in, out, &value, &s.pdf);
    if (!(s.pdf > 0)) return BsdfSample{};
    s.weight = value / s.pdf;
    return s;
}

}  // namespace weft
