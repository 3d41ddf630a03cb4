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
        // The file format holds any float; inference must stay finite.
        model.tNet.checkFiniteOnUnitInputs("t_net");
        model.mNet.checkFiniteOnUnitInputs("m_net");
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

// The smallest probability of a part of the tabulated mixture that may carry energy.
constexpr double kMinimumShare = 1e-3;

}  // namespace

YarnBsdf::YarnBsdf(const YarnModel& model, const std::string& source,
                   const YarnBsdfOptions& options)
    : YarnBsdf(model.colour ? model.forColour(model.fiber.cTT, source) : model, source, options,
               OneColour{}) {}

YarnBsdf::YarnBsdf(const YarnModel& model, const std::string& source,
                   const YarnBsdfOptions& options, OneColour)
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
    if (sampling_ == YarnSampling::Tabulated) buildSamplingTable();
}

YarnSampling parseYarnSampling(const std::string& name, const std::string& what) {
    if (name == "tabulated") return YarnSampling::Tabulated;
    if (name == "fitted") return YarnSampling::Fitted;
    if (name == "cosine") return YarnSampling::Cosine;
    throw InputError(what + " \"" + name +
                     "\": unknown yarn sampling (allowed: tabulated, fitted, cosine)");
}

const char* yarnSamplingName(YarnSampling sampling) {
    switch (sampling) {
        case YarnSampling::Tabulated:
            return "tabulated";
        case YarnSampling::Fitted:
            return "fitted";
        case YarnSampling::Cosine:
            return "cosine";
    }
    return "fitted";
}

size_t YarnBsdf::memoryBytes() const {
    auto bytes = [](const auto& v) { return v.size() * sizeof(v[0]); };
    return sizeof(*this) + rLobe_.fiber().memoryBytes() - sizeof(FiberBcsdf) +
           bytes(guardReflectance_) + bytes(guardEnergyM_) + bytes(guardCell_) + table_.bytes() +
           bytes(peakMasking_) + bytes(tableEnergyM_) + bytes(tableEnergyR_);
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
        // The R table is smooth in fiber angles without the calibration, which is exact at eval
        // time.
        const Rgb kept = keptReflectance(surfaceIncident(wi)) * calibration_.scales(wi).r;
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

YarnBsdf::SurfaceIncident YarnBsdf::surfaceIncident(const Vec3& wi) const {
    SurfaceIncident s;
    s.local = lobes_.frame().toLocal(wi);
    s.angles = FiberBcsdf::anglesOf(s.local);
    s.phi = std::atan2(s.local.y, std::max(s.local.z, 0.0));
    return s;
}

Rgb YarnBsdf::keptReflectance(const SurfaceIncident& surface) const {
    int a0, b0;
    double fa, fb;
    axisCell((surface.angles.theta + kHalfPi) / kPi * (kGuardFiber - 1), kGuardFiber, &a0, &fa);
    axisCell((surface.phi + kHalfPi) / kPi * (kGuardFiber - 1), kGuardFiber, &b0, &fb);
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

YarnBsdf::GuardScales YarnBsdf::scaleUpper(const Vec3& wi, const SurfaceIncident& surface,
                                           double pT,
                                           const EnergyCalibration::Scales& calibration) const {
    GuardScales s;
    if (!guardActive_) return s;
    const GuardCell cell = guardCell(wi);
    if (!guardCell_[static_cast<size_t>(cell.a0) * kGuardPhi + cell.b0]) return s;
    const Rgb kept = keptReflectance(surface) * calibration.r, energy = energyM(cell);
    const Rgb af = rLobe_.fiber().albedo(surface.local);
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
    return scaleUpper(i, surfaceIncident(i), transmissionUpper(i), calibration_.scales(i)).m;
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
    const SurfaceIncident surface = surfaceIncident(wi);
    const GuardScales g = scaleUpper(wi, surface, pT, s);
    Incident in;
    in.pT = in.pickT = pT;
    in.rScale = s.r * g.r;
    in.mScale = s.m * g.m;
    if (hasReflection_) in.fiber = rLobe_.fiber().incident(surface.angles);
    if (table_.empty()) return in;
    // Tabulated sampling (yarn_bsdf.h): the mixture's weights from the
    // energies of its parts.
    in.table = table_.incident(std::clamp(surface.local.x, -1.0, 1.0), surface.angles.theta,
                               surface.phi);
    double peak = 0;
    if (hasReflection_) {
        // theta_i and F(theta_i) of q_R: the R lobe's fiber state has both.
        in.thetaI = in.fiber.angles.theta;
        peak = 0.5 * (1.0 - pT) * (in.fiber.fresnel * in.rScale).average() *
               table_.blend(in.table, peakMasking_);
    }
    // The table's M term, and its R term (the fiber's TT lobe inside S_R) per unit 1 - P(T).
    const double rest =
        table_.blend(in.table, tableEnergyM_) + (1.0 - pT) * table_.blend(in.table, tableEnergyR_);
    const double continuous = peak + rest;
    // q_R keeps a share wherever S_R may be positive, the table wherever S_M may be.
    in.pickR = hasReflection_ ? std::clamp(continuous > 0 ? peak / continuous : 0.5, kMinimumShare,
                                           1.0 - kMinimumShare)
                              : 0.0;
    in.pickT = pT > 0 ? std::min(pT / (pT + continuous), 1.0 - kMinimumShare) : 0.0;
    return in;
}

Rgb YarnBsdf::reflectionPeak(const Vec3& wi, const Vec3& wo, const Incident& in) const {
    if (!hasReflection_ || wi.z <= 0 || wo.z <= 0) return Rgb();
    // FiberBcsdf's R term, F(theta_i) g_R(theta_o; -theta_i) / (2 pi) cos theta_o, in
    // the surface fiber frame, times (1 - P(T)) m and the calibration: S_R's sharp part.
    // theta_i and F(theta_i) come from the R lobe's fiber state, as in incident().
    const FiberBcsdf::Angles out = outAngles(wo);
    const double g = peakLongitudinal().eval(out.theta, -in.fiber.angles.theta);
    return in.fiber.fresnel * in.rScale *
           ((1.0 - in.pT) * g * out.cosTheta / kTwoPi * rLobe_.masking(wi, wo));
}

void YarnBsdf::buildSamplingTable() {
    // The table follows the channel mean of everything but the R peak, in two
    // terms: S_M and the rest of S_R. The mean, not the luminance: one
    // direction serves three channels whose S can differ in shape (cotton's
    // red reflects at the fibers, its blue scatters through them: blue / red
    // reaches 30 away from the specular cone), and a channel's weight S_c /
    // pdf stays below 3 E_mean where the table follows the mean, while
    // luminance (blue 0.07) let blue weights reach 8 times the albedo, which
    // over a near-white yarn's long paths made blue fireflies (docs/yarn.md).
    table_ = SamplingTable(
        lobes_.frame(), 2,
        [this](const Vec3& wi, const std::vector<Vec3>& wo, std::vector<double>& values) {
            const Incident in = incident(wi, transmissionUpper(wi));
            for (size_t k = 0; k < wo.size(); ++k) {
                const Components c = componentsUpper(wi, wo[k], in);
                values[2 * k] = std::max(0.0, c.m.average());
                values[2 * k + 1] =
                    hasReflection_ ? std::max(0.0, (c.r - reflectionPeak(wi, wo[k], in)).average())
                                   : 0.0;
            }
        });
    // Their energies per node, the R term's per unit 1 - P(T), which can
    // change fast with wi (P(T) does near grazing incidence).
    tableEnergyM_.assign(SamplingTable::kNodes, 0.0);
    tableEnergyR_.assign(SamplingTable::kNodes, 0.0);
    for (int node = 0; node < SamplingTable::kNodes; ++node) {
        const Vec3 wi = SamplingTable::nodeDirection(
            lobes_.frame(), node / SamplingTable::kIncidentPhi, node % SamplingTable::kIncidentPhi);
        const double kept = 1.0 - transmissionUpper(wi);
        tableEnergyM_[node] = table_.nodeEnergy(node, 0);
        tableEnergyR_[node] = kept > 0 ? table_.nodeEnergy(node, 1) / kept : 0.0;
    }
    // Mean masking over q_R at every node: theta_o from g cos^2 around
    // -theta_i (Gauss-Legendre panels over +-6 beta_R, weights normalised),
    // phi_o uniform on the half cone.
    peakMasking_.assign(SamplingTable::kNodes, 1.0);
    if (!hasReflection_ || rLobe_.params().masking.empty()) return;
    const SurfaceFiberFrame& frame = lobes_.frame();
    const double beta = peakLongitudinal().beta();
    tbb::parallel_for(0, SamplingTable::kNodes, [&](int node) {
        const Vec3 wi = SamplingTable::nodeDirection(frame, node / SamplingTable::kIncidentPhi,
                                                     node % SamplingTable::kIncidentPhi);
        const double thetaI = frame.longitudinalAngle(wi);
        std::vector<double> thetaEdges, phiEdges, theta, thetaWeight, phi, phiWeight;
        quadrature::uniformEdges(std::max(-kHalfPi, -thetaI - 6 * beta),
                                 std::min(kHalfPi, -thetaI + 6 * beta), 8, &thetaEdges);
        quadrature::uniformEdges(-kHalfPi, kHalfPi, 8, &phiEdges);
        quadrature::panelRule(thetaEdges, &theta, &thetaWeight);
        quadrature::panelRule(phiEdges, &phi, &phiWeight);
        double sum = 0, weightSum = 0;
        for (size_t a = 0; a < theta.size(); ++a) {
            const double w = thetaWeight[a] * peakLongitudinal().eval(theta[a], -thetaI) *
                             sqr(std::cos(theta[a]));
            for (size_t b = 0; b < phi.size(); ++b) {
                sum += w * phiWeight[b] * rLobe_.masking(wi, frame.direction(theta[a], phi[b]));
                weightSum += w * phiWeight[b];
            }
        }
        peakMasking_[node] = weightSum > 0 ? sum / weightSum : 1.0;
    });
}

double YarnBsdf::continuousPdf(const Vec3& wo, const FiberBcsdf::Angles& out,
                               const Incident& in) const {
    double d = 0;
    if (in.pickR > 0 && wo.z > 0)
        d += in.pickR * peakLongitudinal().eval(out.theta, -in.thetaI) * out.cosTheta * kInvPi;
    if (in.pickR < 1) d += (1.0 - in.pickR) * table_.pdf(in.table, wo);
    return (1.0 - in.pickT) * d;
}

Rgb YarnBsdf::evalM(const Vec3& wi, const Vec3& wo) const { return evalScattering(mNet_, wi, wo); }

YarnBsdf::LobeProbabilities YarnBsdf::lobeProbabilities(const Vec3& wi) const {
    if (sampling_ == YarnSampling::Tabulated) {
        const Vec3 i = wi.z < 0 ? mirrored(wi) : wi;
        const Incident in = incident(i, transmissionUpper(i));
        const double continuous = 1.0 - in.pickT;
        return {in.pickT, continuous * in.pickR, continuous * (1.0 - in.pickR)};
    }
    const double pT = transmission(wi);
    if (sampling_ == YarnSampling::Cosine) return {pT, 0.0, 1.0 - pT};
    return {pT, (1.0 - pT) * kappaR_, (1.0 - pT) * (1.0 - kappaR_)};
}

void YarnBsdf::evalAndPdf(const Vec3& wi, const Vec3& wo, const Incident& in, Rgb* value,
                          double* density) const {
    const FiberBcsdf::Angles out =
        value || sampling_ == YarnSampling::Tabulated ? outAngles(wo) : FiberBcsdf::Angles{};
    if (value) {
        const Components parts = componentsUpper(wi, wo, in, out);
        *value = parts.m;
        if (hasReflection_) *value += parts.r;
    }
    if (density && sampling_ == YarnSampling::Tabulated) {
        *density = continuousPdf(wo, out, in);
    } else if (density && sampling_ == YarnSampling::Cosine) {
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
    // The tabulated density needs the whole incident state.
    if (sampling_ == YarnSampling::Tabulated) return Bsdf::pdf(wi, wo);
    // The others need P(T) alone: no calibration or energy guard.
    const bool flip = wi.z < 0;
    const Vec3 i = flip ? mirrored(wi) : wi, o = flip ? mirrored(wo) : wo;
    Incident in;
    in.pT = in.pickT = transmissionUpper(i);
    in.rScale = in.mScale = Rgb(1.0);
    double density;
    evalAndPdf(i, o, in, nullptr, &density);
    return density;
}

YarnBsdf::Components YarnBsdf::components(const Vec3& wi, const Vec3& wo) const {
    const bool flip = wi.z < 0;
    const Vec3 i = flip ? mirrored(wi) : wi, o = flip ? mirrored(wo) : wo;
    return componentsUpper(i, o, incident(i, transmissionUpper(i)));
}

FiberBcsdf::Angles YarnBsdf::outAngles(const Vec3& wo) const {
    if (!hasReflection_ || wo.z <= 0) return {};
    return FiberBcsdf::anglesOf(lobes_.frame().toLocal(wo));
}

YarnBsdf::Components YarnBsdf::componentsUpper(const Vec3& wi, const Vec3& wo,
                                               const Incident& in) const {
    return componentsUpper(wi, wo, in, outAngles(wo));
}

YarnBsdf::Components YarnBsdf::componentsUpper(const Vec3& wi, const Vec3& wo, const Incident& in,
                                               const FiberBcsdf::Angles& out) const {
    Components c;
    c.pT = in.pT;
    if (hasReflection_) c.r = rLobe_.eval(wi, wo, in.fiber, out, in.pT) * in.rScale;
    c.m = evalM(wi, wo) * in.mScale;
    return c;
}

BsdfSample YarnBsdf::sample(const BsdfIncident& in, const BsdfSampleInput& u, Rng& rng) const {
    const Prepared& p = in.get<Prepared>();
    const double pT = p.in.pT, pickT = p.in.pickT;
    BsdfSample s;
    if (u[0] < pickT) {
        // S_T = P(T|wi) delta(wo + wi), chosen with probability P_T (P(T|wi)
        // unless the sampling is tabulated).
        s.wo = -in.wi();
        s.weight = Rgb(pT / pickT);
        s.pdf = 0;
        s.lobe = kLobeT;
        s.isDelta = true;
        return s;
    }
    const double pR = (1.0 - pT) * kappaR_, pM = (1.0 - pT) * (1.0 - kappaR_);
    Vec3 o;
    if (sampling_ == YarnSampling::Tabulated) {
        // The rest of u[0], rescaled to [0, 1), picks q_R or the table, then the table's node.
        const double uPart = std::clamp((u[0] - pickT) / (1.0 - pickT), 0.0, kOneMinusEpsilon);
        if (uPart < p.in.pickR) {
            s.lobe = kLobeR;
            const double thetaO = peakLongitudinal().sample(-p.in.thetaI, u[1], rng);
            o = lobes_.frame().direction(thetaO, kPi * (u[2] - 0.5));
        } else {
            s.lobe = kLobeM;
            const double uNode =
                std::clamp((uPart - p.in.pickR) / (1.0 - p.in.pickR), 0.0, kOneMinusEpsilon);
            o = table_.sample(p.in.table, uNode, u[1], u[2]);
        }
    } else if (sampling_ == YarnSampling::Cosine) {
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
        const double uLobe = std::clamp((u[0] - pT - pR) / pM, 0.0, kOneMinusEpsilon);
        o = lobes_.sampleM(p.upper, uLobe, u[1], u[2], rng);
    }
    BsdfEval e;
    evalAndPdf(p.upper, o, p.in, &e.value, &e.pdf);
    return BsdfSample::fromEval(p.flip ? mirrored(o) : o, e, s.lobe);
}

}  // namespace weft
