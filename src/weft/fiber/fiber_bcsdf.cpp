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

size_t FiberBcsdf::memoryBytes() const {
    return sizeof(*this) - 2 * sizeof(LongitudinalGaussian) + gR_.memoryBytes() +
           gTT_.memoryBytes();
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

double FiberBcsdf::probabilityR(const Rgb& f, const Rgb& importance) const {
    const double energyR = (f * importance).average();
    const double energyTT = ((Rgb(1.0) - f) * params_.cTT * importance).average();
    const double total = energyR + energyTT;
    return total > 0 ? energyR / total : 0.5;
}

FiberBcsdf::Incident FiberBcsdf::incident(const Vec3& wi, const Rgb& importance) const {
    return incident(anglesOf(wi), importance);
}

FiberBcsdf::Incident FiberBcsdf::incident(const Angles& wi, const Rgb& importance) const {
    const Rgb f = fresnel(wi.cosTheta);
    return Incident{wi, f, probabilityR(f, importance)};
}

void FiberBcsdf::prepare(const Vec3& wi, BsdfIncident& in) const {
    in.emplace(wi, incident(wi, in.importance()));
}

Rgb FiberBcsdf::evalPrepared(const Incident& in, const Angles& out) const {
    Rgb value;
    evalAndPdf(in, out, &value, nullptr);
    return value;
}

BsdfEval FiberBcsdf::evalPdfPrepared(const Incident& in, const Angles& out) const {
    BsdfEval e;
    evalAndPdf(in, out, &e.value, &e.pdf);
    return e;
}

void FiberBcsdf::evalAndPdf(const Incident& incident, const Angles& out, Rgb* value,
                            double* density) const {
    if (out.cosTheta <= 0) {
        if (value) *value = Rgb();
        if (density) *density = 0;
        return;
    }
    const Angles& in = incident.angles;
    const Rgb& f = incident.fresnel;
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
    // eval = S_f cos(theta_o) (docs/design.md 3).
    if (value) *value = (f * (gR * nR) + params_.cTT * (Rgb(1.0) - f) * (gTT * nTT)) * out.cosTheta;
    if (density) {
        // (theta, phi) density p_R gR cos^2 nR + p_TT gTT cos^2 nTT, over cos(theta_o).
        const double pR = incident.probabilityR;
        *density = (pR * gR * nR + (1.0 - pR) * gTT * nTT) * out.cosTheta;
    }
}

BsdfEval FiberBcsdf::evalPdf(const BsdfIncident& in, const Vec3& wo) const {
    return evalPdfPrepared(in.get<Incident>(), anglesOf(wo));
}

Rgb FiberBcsdf::eval(const BsdfIncident& in, const Vec3& wo) const {
    return evalPrepared(in.get<Incident>(), anglesOf(wo));
}

double FiberBcsdf::pdf(const BsdfIncident& in, const Vec3& wo) const {
    double density;
    evalAndPdf(in.get<Incident>(), anglesOf(wo), nullptr, &density);
    return density;
}

BsdfSample FiberBcsdf::sample(const BsdfIncident& incident, const BsdfSampleInput& u,
                              Rng& rng) const {
    const Incident& inc = incident.get<Incident>();
    const Angles& in = inc.angles;
    const int lobe = u[0] < inc.probabilityR ? kLobeR : kLobeTT;
    const LongitudinalGaussian& g = lobe == kLobeR ? gR_ : gTT_;
    const double thetaO = g.sample(-in.theta, u[1], rng);
    // Azimuth as a unit vector (cos phi_o, sin phi_o) in the y-z plane.
    double cosPhiO, sinPhiO;
    if (lobe == kLobeR) {
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
    const Vec3 wo = {sinThetaO, cosThetaO * cosPhiO, cosThetaO * sinPhiO};
    // The angles of wo are known: no need for anglesOf(wo).
    const Angles out{sinThetaO, cosThetaO, thetaO, wo.y, wo.z};
    BsdfEval e;
    evalAndPdf(inc, out, &e.value, &e.pdf);
    return BsdfSample::fromEval(wo, e, lobe);
}

}  // namespace weft
