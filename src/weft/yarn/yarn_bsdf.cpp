#include "weft/yarn/yarn_bsdf.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/math.h"
#include "weft/core/quadrature.h"
#include "weft/core/sampling.h"
#include "weft/yarn/sphere_rule.h"

namespace weft {

namespace {

// The model's own checks (yarn_model.h), before any member is built.
const YarnModel& validated(const YarnModel& model, const std::string& source) {
    try {
        model.validate();
    } catch (const InputError& e) {
        throw InputError(source + ": " + e.what());
    }
    return model;
}

// Builds a member, prefixing the InputError of its constructor with `source`.
template <typename T, typename... Args>
T withSource(const std::string& source, const Args&... args) {
    try {
        return T(args...);
    } catch (const InputError& e) {
        throw InputError(source + ": " + e.what());
    }
}

constexpr Vec3 mirrored(const Vec3& w) { return {w.x, w.y, -w.z}; }

}  // namespace

YarnBsdf::YarnBsdf(const YarnModel& model, const std::string& source,
                   const YarnBsdfOptions& options)
    : tNet_(validated(model, source).tNet, source + ": t_net"),
      mNet_(model.mNet, source + ": m_net"),
      rLobe_(withSource<RLobe>(source, model.fiber, model.rLobe)),
      lobes_(withSource<SamplingLobes>(source, model.fiber, model.rLobe.tiltDeg, model.sampling)),
      ablation_(model.ablation),
      hasTransmission_(model.hasTransmissionLobe()),
      hasReflection_(model.hasReflectionLobe()),
      sampling_(options.sampling),
      kappaR_(hasReflection_ ? model.sampling.kappaR : 0.0),
      calibration_(model.calibration) {
    if (options.energyGuard) buildEnergyGuard();
}

YarnSampling parseYarnSampling(const std::string& name, const std::string& what) {
    if (name == "fitted") return YarnSampling::Fitted;
    if (name == "cosine") return YarnSampling::Cosine;
    throw InputError(what + " \"" + name + "\": unknown yarn sampling (allowed: fitted, cosine)");
}

const char* yarnSamplingName(YarnSampling sampling) {
    return sampling == YarnSampling::Cosine ? "cosine" : "fitted";
}

YarnBsdf YarnBsdf::load(const std::string& path, const YarnBsdfOptions& options) {
    return YarnBsdf(loadYarnModel(path), path, options);
}

// ------------------------------------------------------------ energy guard --

double YarnBsdf::guardPolarAngle(int index) {
    const double u = 1.0 - static_cast<double>(index) / (kGuardTheta - 1);
    return kHalfPi * (1.0 - u * u);
}

double YarnBsdf::guardFiberAngle(int index) { return -kHalfPi + kPi * index / (kGuardFiber - 1); }

namespace {

// Cell and fraction of `t` (in node units) on an axis of `count` nodes.
void axisCell(double t, int count, int* i0, double* f) {
    *i0 = std::clamp(static_cast<int>(std::floor(t)), 0, count - 2);
    *f = std::clamp(t - *i0, 0.0, 1.0);
}

}  // namespace

void YarnBsdf::buildEnergyGuard() {
    using quadrature::uniformEdges;
    const SurfaceFiberFrame& frame = lobes_.frame();
    const double betaR = radians(rLobe_.fiber().params().betaRDeg);
    // Outgoing rules in the surface fiber frame (sphere_rule.h; yarn_integrals.h
    // uses the finer one of the checks): M is smooth, 8 x 8 panels over the
    // sphere; R lives on the upper half cone |phi| < pi/2, within a few beta_R
    // of theta = -theta_i for the fiber's R lobe, wider for its TT lobe.
    std::vector<double> thetaEdgesM, phiEdgesM, phiEdgesR;
    uniformEdges(-kHalfPi, kHalfPi, 8, &thetaEdgesM);
    uniformEdges(-kPi, kPi, 8, &phiEdgesM);
    uniformEdges(-kHalfPi, kHalfPi, 4, &phiEdgesR);
    const SphereRule ruleM = surfaceFiberRule(frame, thetaEdgesM, phiEdgesM);

    const size_t fiberNodes = static_cast<size_t>(kGuardFiber) * kGuardFiber;
    const size_t nodes = static_cast<size_t>(kGuardTheta) * kGuardPhi;
    guardReflectance_.assign(fiberNodes, Rgb());
    guardEnergyM_.assign(nodes, Rgb());
    // R table, in surface-fiber angles (zeros without an R lobe: E_R = 0).
    tbb::parallel_for(size_t(0), fiberNodes, [&](size_t node) {
        if (!hasReflection_) return;
        const double thetaI = guardFiberAngle(static_cast<int>(node / kGuardFiber));
        const Vec3 wi =
            frame.direction(thetaI, guardFiberAngle(static_cast<int>(node % kGuardFiber)));
        const double pT = transmissionUpper(wi);
        std::vector<double> thetaEdges;
        uniformEdges(-kHalfPi, kHalfPi, 12, &thetaEdges);
        uniformEdges(std::max(-kHalfPi, -thetaI - 5 * betaR),
                     std::min(kHalfPi, -thetaI + 5 * betaR), 10, &thetaEdges);
        std::sort(thetaEdges.begin(), thetaEdges.end());
        const SphereRule ruleR = surfaceFiberRule(frame, thetaEdges, phiEdgesR);
        Rgb energyR;
        for (size_t k = 0; k < ruleR.directions.size(); ++k)
            energyR += rLobe_.eval(wi, ruleR.directions[k], pT) * ruleR.weights[k];
        const Rgb af = rLobe_.fiber().albedo(frame.toLocal(wi));
        for (int c = 0; c < 3; ++c) {
            const double full = (1.0 - pT) * af[c];
            guardReflectance_[node][c] = full > 0 ? energyR[c] / full : 0.0;
        }
    });
    // M table, in yarn angles; the guard is needed if any node's albedo comes near 1.
    std::vector<double> albedo(nodes, 0.0);
    tbb::parallel_for(size_t(0), nodes, [&](size_t node) {
        const Vec3 wi =
            sphericalDirection(guardPolarAngle(static_cast<int>(node / kGuardPhi)),
                               -kPi + kTwoPi * static_cast<double>(node % kGuardPhi) / kGuardPhi);
        Rgb energy;
        for (size_t k = 0; k < ruleM.directions.size(); ++k)
            energy += evalM(wi, ruleM.directions[k]) * ruleM.weights[k];
        energy = energy * calibration_.scales(wi).m;
        guardEnergyM_[node] = energy;
        const double pT = transmissionUpper(wi);
        // The R table is smooth in fiber angles without the calibration, which is exact at eval time.
        const Rgb kept = keptReflectance(wi) * calibration_.scales(wi).r;
        const Rgb af = rLobe_.fiber().albedo(frame.toLocal(wi));
        for (int c = 0; c < 3; ++c)
            albedo[node] = std::max(albedo[node], pT + (1.0 - pT) * kept[c] * af[c] + energy[c]);
    });
    // A cell between rows a, a + 1 and columns b, b + 1 needs the guard if any
    // node its cubic interpolation reads (rows a - 1 to a + 2) comes near 1;
    // elsewhere s = 1 without further lookups.
    guardCell_.assign(nodes, 0);
    for (int a = 0; a + 1 < kGuardTheta; ++a)
        for (int b = 0; b < kGuardPhi; ++b)
            for (int r = std::max(a - 1, 0); r <= std::min(a + 2, kGuardTheta - 1); ++r)
                for (int q : {b, (b + 1) % kGuardPhi})
                    if (albedo[static_cast<size_t>(r) * kGuardPhi + q] > kGuardThreshold)
                        guardCell_[static_cast<size_t>(a) * kGuardPhi + b] = 1;
    guardActive_ = std::find(guardCell_.begin(), guardCell_.end(), 1) != guardCell_.end();
}

Rgb YarnBsdf::keptReflectance(const Vec3& wi) const {
    const Vec3 local = lobes_.frame().toLocal(wi);
    const double theta = safeAsin(local.x), phi = std::atan2(local.y, std::max(local.z, 0.0));
    int a0, b0;
    double fa, fb;
    axisCell((theta + kHalfPi) / kPi * (kGuardFiber - 1), kGuardFiber, &a0, &fa);
    axisCell((phi + kHalfPi) / kPi * (kGuardFiber - 1), kGuardFiber, &b0, &fb);
    auto at = [&](int a, int b) {
        return guardReflectance_[static_cast<size_t>(a) * kGuardFiber + b];
    };
    return (at(a0, b0) * (1 - fb) + at(a0, b0 + 1) * fb) * (1 - fa) +
           (at(a0 + 1, b0) * (1 - fb) + at(a0 + 1, b0 + 1) * fb) * fa;
}

YarnBsdf::GuardCell YarnBsdf::guardCell(const Vec3& wi) const {
    // Polar angle -> row (the inverse of guardPolarAngle); azimuth periodic.
    GuardCell cell;
    const double theta = safeAcos(wi.z);
    axisCell((1.0 - std::sqrt(std::max(0.0, 1.0 - theta / kHalfPi))) * (kGuardTheta - 1),
             kGuardTheta, &cell.a0, &cell.fa);
    const double p = (std::atan2(wi.y, wi.x) + kPi) / kTwoPi * kGuardPhi;
    const int b = static_cast<int>(std::floor(p));
    cell.fb = std::clamp(p - b, 0.0, 1.0);
    cell.b0 = ((b % kGuardPhi) + kGuardPhi) % kGuardPhi;
    cell.b1 = (cell.b0 + 1) % kGuardPhi;
    return cell;
}

Rgb YarnBsdf::energyM(const GuardCell& cell) const {
    // Cubic (Catmull-Rom) across rows: E_M bends sharply near grazing
    // incidence, where linear interpolation would underestimate it; linear
    // across azimuths.
    auto row = [&](int a) {
        a = std::clamp(a, 0, kGuardTheta - 1);
        const size_t base = static_cast<size_t>(a) * kGuardPhi;
        return guardEnergyM_[base + cell.b0] * (1 - cell.fb) +
               guardEnergyM_[base + cell.b1] * cell.fb;
    };
    const Rgb pm = row(cell.a0 - 1), p0 = row(cell.a0), p1 = row(cell.a0 + 1),
              p2 = row(cell.a0 + 2);
    const double t = cell.fa, t2 = t * t, t3 = t2 * t;
    Rgb value = (p0 * 2.0 + (p1 - pm) * t + (pm * 2.0 - p0 * 5.0 + p1 * 4.0 - p2) * t2 +
                 (p0 * 3.0 - pm - p1 * 3.0 + p2) * t3) *
                0.5;
    for (int c = 0; c < 3; ++c) value[c] = std::max(value[c], 0.0);
    return value;
}

YarnBsdf::GuardScales YarnBsdf::scaleUpper(const Vec3& wi, double pT,
                                           const EnergyCalibration::Scales& calibration) const {
    GuardScales s;
    if (!guardActive_) return s;
    const GuardCell cell = guardCell(wi);
    if (!guardCell_[static_cast<size_t>(cell.a0) * kGuardPhi + cell.b0]) return s;
    const Rgb kept = keptReflectance(wi) * calibration.r, energy = energyM(cell);
    const Rgb af = rLobe_.fiber().albedo(lobes_.frame().toLocal(wi));
    for (int c = 0; c < 3; ++c) {
        // R alone can exceed 1 - P(T) only through an energy calibration above 1.
        const double r = kept[c] * af[c];
        if (r > 1) s.r[c] = 1 / r;
        const double room = std::max(0.0, (1.0 - pT) * (1.0 - std::min(r, 1.0)));
        if (energy[c] > room) s.m[c] = room / energy[c];
    }
    return s;
}

Rgb YarnBsdf::multipleScatteringScale(const Vec3& wi) const {
    const Vec3 i = wi.z < 0 ? mirrored(wi) : wi;
    return scaleUpper(i, transmissionUpper(i), calibration_.scales(i)).m;
}

// -------------------------------------------------------------- the BSDF --

double YarnBsdf::transmissionUpper(const Vec3& wi) const {
    return hasTransmission_ ? evalTransmission(tNet_, wi) : 0.0;
}

double YarnBsdf::transmission(const Vec3& wi) const {
    return transmissionUpper(wi.z < 0 ? mirrored(wi) : wi);
}

YarnBsdf::Incident YarnBsdf::incident(const Vec3& wi, double pT) const {
    const EnergyCalibration::Scales s = calibration_.scales(wi);
    const GuardScales g = scaleUpper(wi, pT, s);
    return {pT, s.r * g.r, s.m * g.m};
}

Rgb YarnBsdf::evalM(const Vec3& wi, const Vec3& wo) const { return evalScattering(mNet_, wi, wo); }

YarnBsdf::LobeProbabilities YarnBsdf::lobeProbabilities(const Vec3& wi) const {
    const double pT = transmission(wi);
    if (sampling_ == YarnSampling::Cosine) return {pT, 0.0, 1.0 - pT};
    return {pT, (1.0 - pT) * kappaR_, (1.0 - pT) * (1.0 - kappaR_)};
}

void YarnBsdf::evalAndPdf(const Vec3& wi, const Vec3& wo, const Incident& in, Rgb* value,
                          double* density) const {
    if (value) {
        const Components parts = componentsUpper(wi, wo, in);
        *value = parts.m;
        if (hasReflection_) *value += parts.r;
    }
    if (density && sampling_ == YarnSampling::Cosine) {
        // Cosine about n on the side of wo, each side with probability 1/2.
        *density = (1.0 - in.pT) * std::fabs(wo.z) * (0.5 * kInvPi);
    } else if (density) {
        // Paper eq. 10-11: the continuous mixture p_R pdf_R + p_M pdf_M.
        const double pR = (1.0 - in.pT) * kappaR_, pM = (1.0 - in.pT) * (1.0 - kappaR_);
        double d = 0;
        if (pR > 0) d += pR * lobes_.pdfR(wi, wo);
        if (pM > 0) d += pM * lobes_.pdfM(wi, wo);
        *density = d;
    }
}

void YarnBsdf::prepare(const Vec3& wi, BsdfIncident& in) const {
    Prepared p;
    p.flip = wi.z < 0;
    p.upper = p.flip ? mirrored(wi) : wi;
    p.in = incident(p.upper, transmissionUpper(p.upper));
    in.emplace(wi, p);
}

BsdfEval YarnBsdf::evalPdf(const BsdfIncident& in, const Vec3& wo) const {
    const Prepared& p = in.get<Prepared>();
    BsdfEval e;
    evalAndPdf(p.upper, p.flip ? mirrored(wo) : wo, p.in, &e.value, &e.pdf);
    return e;
}

Rgb YarnBsdf::eval(const BsdfIncident& in, const Vec3& wo) const {
    const Prepared& p = in.get<Prepared>();
    Rgb value;
    evalAndPdf(p.upper, p.flip ? mirrored(wo) : wo, p.in, &value, nullptr);
    return value;
}

double YarnBsdf::pdf(const BsdfIncident& in, const Vec3& wo) const {
    const Prepared& p = in.get<Prepared>();
    double density;
    evalAndPdf(p.upper, p.flip ? mirrored(wo) : wo, p.in, nullptr, &density);
    return density;
}

double YarnBsdf::pdf(const Vec3& wi, const Vec3& wo) const {
    // The density needs P(T) alone: no calibration or energy guard.
    const bool flip = wi.z < 0;
    const Vec3 i = flip ? mirrored(wi) : wi, o = flip ? mirrored(wo) : wo;
    double density;
    evalAndPdf(i, o, {transmissionUpper(i), Rgb(1.0), Rgb(1.0)}, nullptr, &density);
    return density;
}

YarnBsdf::Components YarnBsdf::components(const Vec3& wi, const Vec3& wo) const {
    const bool flip = wi.z < 0;
    const Vec3 i = flip ? mirrored(wi) : wi, o = flip ? mirrored(wo) : wo;
    return componentsUpper(i, o, incident(i, transmissionUpper(i)));
}

YarnBsdf::Components YarnBsdf::componentsUpper(const Vec3& wi, const Vec3& wo,
                                               const Incident& in) const {
    Components c;
    c.pT = in.pT;
    if (hasReflection_) c.r = rLobe_.eval(wi, wo, in.pT) * in.rScale;
    c.m = evalM(wi, wo) * in.mScale;
    return c;
}

BsdfSample YarnBsdf::sample(const BsdfIncident& in, const BsdfSampleInput& u, Rng& rng) const {
    const Prepared& p = in.get<Prepared>();
    const double pT = p.in.pT;
    BsdfSample s;
    if (u[0] < pT) {
        // S_T = P(T|wi) delta(wo + wi), chosen with probability p_T = P(T|wi).
        s.wo = -in.wi();
        s.weight = Rgb(1.0);
        s.pdf = 0;
        s.lobe = kLobeT;
        s.isDelta = true;
        return s;
    }
    const double pR = (1.0 - pT) * kappaR_, pM = (1.0 - pT) * (1.0 - kappaR_);
    Vec3 o;
    if (sampling_ == YarnSampling::Cosine) {
        s.lobe = kLobeM;
        // The rest of u[0], rescaled to [0, 1), picks the side of the surface.
        const double uSide = (u[0] - pT) / (1.0 - pT);
        o = sampleCosineHemisphere(u[1], u[2]);
        if (!(uSide < 0.5)) o.z = -o.z;
    } else if (u[0] < pT + pR || !(pM > 0)) {
        s.lobe = kLobeR;
        o = lobes_.sampleR(p.upper, u[1], u[2]);
    } else {
        s.lobe = kLobeM;
        // The rest of u[0], rescaled to [0, 1), picks the cone or the uniform part of pdf_M.
        const double uLobe = std::clamp((u[0] - pT - pR) / pM, 0.0, 0x1.fffffffffffffp-1);
        o = lobes_.sampleM(p.upper, uLobe, u[1], u[2], rng);
    }
    BsdfEval e;
    evalAndPdf(p.upper, o, p.in, &e.value, &e.pdf);
    return BsdfSample::fromEval(p.flip ? mirrored(o) : o, e, s.lobe);
}

}  // namespace weft
