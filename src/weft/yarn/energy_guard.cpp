#include "weft/yarn/energy_guard.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "weft/core/math.h"
#include "weft/core/quadrature.h"
#include "weft/yarn/sphere_rule.h"
#include "weft/yarn/yarn_evaluator.h"

namespace weft {

namespace {

// Cell and fraction of `t` (in node units) on an axis of `count` nodes.
void axisCell(double t, int count, int* i0, double* f) {
    *i0 = std::clamp(static_cast<int>(std::floor(t)), 0, count - 2);
    *f = std::clamp(t - *i0, 0.0, 1.0);
}

}  // namespace

double EnergyGuard::polarAngle(int index) {
    const double u = 1.0 - static_cast<double>(index) / (kTheta - 1);
    return kHalfPi * (1.0 - u * u);
}

double EnergyGuard::fiberAngle(int index) { return -kHalfPi + kPi * index / (kFiber - 1); }

EnergyGuard::EnergyGuard(const YarnEvaluator& model) {
    using quadrature::uniformEdges;
    const SurfaceFiberFrame& frame = model.frame();
    const RLobe& rLobe = model.rLobe();
    const double betaR = radians(rLobe.fiber().params().betaRDeg);
    // Outgoing rules in the surface fiber frame (sphere_rule.h; yarn_integrals.h
    // uses the finer one of the checks): M, mLobeSphereRule; R lives on the
    // upper half cone |phi| < pi/2, within a few beta_R of theta = -theta_i
    // for the fiber's R lobe, wider for its TT lobe: 6 + 5 x 2 panels hold
    // E_R within 1e-3 of twice as many per axis, at a quarter of the load time.
    std::vector<double> phiEdgesR;
    uniformEdges(-kHalfPi, kHalfPi, 2, &phiEdgesR);
    const SphereRule ruleM = mLobeSphereRule(frame);

    const size_t fiberNodes = static_cast<size_t>(kFiber) * kFiber;
    const size_t nodes = static_cast<size_t>(kTheta) * kPhi;
    reflectance_.assign(fiberNodes, Rgb());
    energyM_.assign(nodes, Rgb());
    // R table, in surface-fiber angles (zeros without an R lobe: E_R = 0).
    tbb::parallel_for(size_t(0), fiberNodes, [&](size_t node) {
        if (!model.hasReflection()) return;
        const double thetaI = fiberAngle(static_cast<int>(node / kFiber));
        const Vec3 wi = frame.direction(thetaI, fiberAngle(static_cast<int>(node % kFiber)));
        const double pT = model.transmission(wi);
        std::vector<double> thetaEdges;
        uniformEdges(-kHalfPi, kHalfPi, 6, &thetaEdges);
        uniformEdges(std::max(-kHalfPi, -thetaI - 5 * betaR),
                     std::min(kHalfPi, -thetaI + 5 * betaR), 5, &thetaEdges);
        std::sort(thetaEdges.begin(), thetaEdges.end());
        const SphereRule ruleR = surfaceFiberRule(frame, thetaEdges, phiEdgesR);
        Rgb energyR;
        for (size_t k = 0; k < ruleR.directions.size(); ++k)
            energyR += rLobe.eval(wi, ruleR.directions[k], pT) * ruleR.weights[k];
        const Rgb af = rLobe.fiber().albedo(frame.toLocal(wi));
        for (int c = 0; c < 3; ++c) {
            const double full = (1.0 - pT) * af[c];
            reflectance_[node][c] = full > 0 ? energyR[c] / full : 0.0;
        }
    });
    // M table, in yarn angles; the guard is needed if any node's albedo comes near 1.
    std::vector<double> albedo(nodes, 0.0);
    tbb::parallel_for(size_t(0), nodes, [&](size_t node) {
        const Vec3 wi =
            sphericalDirection(polarAngle(static_cast<int>(node / kPhi)),
                               -kPi + kTwoPi * static_cast<double>(node % kPhi) / kPhi);
        std::vector<Rgb> m(ruleM.directions.size());
        model.evalMBatch(wi, ruleM.directions.data(), m.size(), m.data());
        Rgb energy;
        for (size_t k = 0; k < m.size(); ++k) energy += m[k] * ruleM.weights[k];
        energy = energy * model.calibration(wi).m;
        energyM_[node] = energy;
        const double pT = model.transmission(wi);
        // The R table is smooth in fiber angles without the calibration, which
        // is exact at eval time.
        const Rgb kept = keptReflectance(model.surfaceAngles(wi)) * model.calibration(wi).r;
        const Rgb af = rLobe.fiber().albedo(frame.toLocal(wi));
        for (int c = 0; c < 3; ++c)
            albedo[node] = std::max(albedo[node], pT + (1.0 - pT) * kept[c] * af[c] + energy[c]);
    });
    // A cell between rows a, a + 1 and columns b, b + 1 needs the guard if any
    // node its cubic interpolation reads (rows a - 1 to a + 2) comes near 1;
    // elsewhere s = 1 without further lookups.
    guarded_.assign(nodes, 0);
    for (int a = 0; a + 1 < kTheta; ++a)
        for (int b = 0; b < kPhi; ++b)
            for (int r = std::max(a - 1, 0); r <= std::min(a + 2, kTheta - 1); ++r)
                for (int q : {b, (b + 1) % kPhi})
                    if (albedo[static_cast<size_t>(r) * kPhi + q] > kThreshold)
                        guarded_[static_cast<size_t>(a) * kPhi + b] = 1;
    active_ = std::find(guarded_.begin(), guarded_.end(), 1) != guarded_.end();
}

size_t EnergyGuard::memoryBytes() const {
    return reflectance_.size() * sizeof(Rgb) + energyM_.size() * sizeof(Rgb) + guarded_.size();
}

Rgb EnergyGuard::keptReflectance(const SurfaceFiberAngles& surface) const {
    int a0, b0;
    double fa, fb;
    axisCell((surface.angles.theta + kHalfPi) / kPi * (kFiber - 1), kFiber, &a0, &fa);
    axisCell((surface.phi + kHalfPi) / kPi * (kFiber - 1), kFiber, &b0, &fb);
    auto at = [&](int a, int b) { return reflectance_[static_cast<size_t>(a) * kFiber + b]; };
    return (at(a0, b0) * (1 - fb) + at(a0, b0 + 1) * fb) * (1 - fa) +
           (at(a0 + 1, b0) * (1 - fb) + at(a0 + 1, b0 + 1) * fb) * fa;
}

EnergyGuard::Cell EnergyGuard::cellOf(const Vec3& wi) const {
    // Polar angle -> row (the inverse of polarAngle); azimuth periodic.
    Cell cell;
    const double theta = safeAcos(wi.z);
    axisCell((1.0 - std::sqrt(std::max(0.0, 1.0 - theta / kHalfPi))) * (kTheta - 1), kTheta,
             &cell.a0, &cell.fa);
    const double p = (std::atan2(wi.y, wi.x) + kPi) / kTwoPi * kPhi;
    const int b = static_cast<int>(std::floor(p));
    cell.fb = std::clamp(p - b, 0.0, 1.0);
    cell.b0 = ((b % kPhi) + kPhi) % kPhi;
    cell.b1 = (cell.b0 + 1) % kPhi;
    return cell;
}

Rgb EnergyGuard::energyM(const Cell& cell) const {
    // Cubic (Catmull-Rom) across rows: E_M bends sharply near grazing
    // incidence, where linear interpolation would underestimate it; linear
    // across azimuths.
    auto row = [&](int a) {
        a = std::clamp(a, 0, kTheta - 1);
        const size_t base = static_cast<size_t>(a) * kPhi;
        return energyM_[base + cell.b0] * (1 - cell.fb) + energyM_[base + cell.b1] * cell.fb;
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

EnergyGuard::Scales EnergyGuard::scales(const Vec3& wi, const SurfaceFiberAngles& surface,
                                        double pT, const EnergyCalibration::Scales& calibration,
                                        const FiberBcsdf& fiber) const {
    Scales s;
    if (!active_) return s;
    const Cell cell = cellOf(wi);
    if (!guarded_[static_cast<size_t>(cell.a0) * kPhi + cell.b0]) return s;
    const Rgb kept = keptReflectance(surface) * calibration.r, energy = energyM(cell);
    const Rgb af = fiber.albedo(surface.local);
    for (int c = 0; c < 3; ++c) {
        // R alone can exceed 1 - P(T) only through an energy calibration above 1.
        const double r = kept[c] * af[c];
        if (r > 1) s.r[c] = 1 / r;
        const double room = std::max(0.0, (1.0 - pT) * (1.0 - std::min(r, 1.0)));
        if (energy[c] > room) s.m[c] = room / energy[c];
    }
    return s;
}

}  // namespace weft
