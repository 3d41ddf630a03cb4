#include "weft/yarn/tabulated_sampler.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "weft/core/math.h"
#include "weft/core/quadrature.h"
#include "weft/yarn/yarn_evaluator.h"

namespace weft {

namespace {

// The smallest probability of a part of the mixture that may carry energy.
constexpr double kMinimumShare = 1e-3;

// The fiber's R lobe inside S_R, calibration applied: F(theta_i) g_R(theta_o;
// -theta_i) / (2 pi) cos theta_o in the surface fiber frame, times (1 - P(T))
// m, S_R's sharp part. theta_i and F(theta_i) come from the R lobe's fiber
// state, as in prepare().
Rgb reflectionPeak(const YarnEvaluator& model, const Vec3& wo, const YarnIncident& in) {
    if (!model.hasReflection() || in.wi.z <= 0 || wo.z <= 0) return Rgb();
    const FiberBcsdf::Angles out = model.outAngles(wo);
    const double g =
        model.rLobe().fiber().longitudinalR().eval(out.theta, -in.fiber.angles.theta);
    return in.fiber.fresnel * in.rScale *
           ((1.0 - in.pT) * g * out.cosTheta / kTwoPi * model.rLobe().masking(in.wi, wo));
}

}  // namespace

TabulatedYarnSampler::TabulatedYarnSampler(std::shared_ptr<const YarnEvaluator> evaluator)
    : model_(std::move(evaluator)), hasReflection_(model_->hasReflection()), frame_(model_->frame()) {
    const YarnEvaluator& model = *model_;
    // The table follows the channel mean of everything but the R peak, in two
    // terms: S_M and the rest of S_R. The mean, not the luminance: one
    // direction serves three channels whose S can differ in shape (cotton's
    // red reflects at the fibers, its blue scatters through them: blue / red
    // reaches 30 away from the specular cone), and a channel's weight S_c /
    // pdf stays below 3 E_mean where the table follows the mean, while
    // luminance (blue 0.07) let blue weights reach 8 times the albedo, which
    // over a near-white yarn's long paths made blue fireflies (docs/yarn.md).
    table_ = SamplingTable(
        frame_, 2, [&](const Vec3& wi, const std::vector<Vec3>& wo, std::vector<double>& values) {
            const YarnIncident in = model.incident(wi);
            std::vector<YarnComponents> components(wo.size());
            model.componentsBatch(wo.data(), wo.size(), in, components.data());
            for (size_t k = 0; k < wo.size(); ++k) {
                const YarnComponents& c = components[k];
                values[2 * k] = std::max(0.0, c.m.average());
                values[2 * k + 1] =
                    hasReflection_
                        ? std::max(0.0, (c.r - reflectionPeak(model, wo[k], in)).average())
                        : 0.0;
            }
        });
    // Their energies per node, the R term's per unit 1 - P(T), which can
    // change fast with wi (P(T) does near grazing incidence).
    tableEnergyM_.assign(SamplingTable::kNodes, 0.0);
    tableEnergyR_.assign(SamplingTable::kNodes, 0.0);
    for (int node = 0; node < SamplingTable::kNodes; ++node) {
        const Vec3 wi = SamplingTable::nodeDirection(frame_, node / SamplingTable::kIncidentPhi,
                                                     node % SamplingTable::kIncidentPhi);
        const double kept = 1.0 - model.transmission(wi);
        tableEnergyM_[node] = table_.nodeEnergy(node, 0);
        tableEnergyR_[node] = kept > 0 ? table_.nodeEnergy(node, 1) / kept : 0.0;
    }
    // Mean masking over q_R at every node: theta_o from g cos^2 around
    // -theta_i (Gauss-Legendre panels over +-6 beta_R, weights normalised),
    // phi_o uniform on the half cone.
    peakMasking_.assign(SamplingTable::kNodes, 1.0);
    if (!hasReflection_ || model.rLobe().params().masking.empty()) return;
    const double beta = peak().beta();
    tbb::parallel_for(0, SamplingTable::kNodes, [&](int node) {
        const Vec3 wi = SamplingTable::nodeDirection(frame_, node / SamplingTable::kIncidentPhi,
                                                     node % SamplingTable::kIncidentPhi);
        const double thetaI = frame_.longitudinalAngle(wi);
        std::vector<double> thetaEdges, phiEdges, theta, thetaWeight, phi, phiWeight;
        quadrature::uniformEdges(std::max(-kHalfPi, -thetaI - 6 * beta),
                                 std::min(kHalfPi, -thetaI + 6 * beta), 8, &thetaEdges);
        quadrature::uniformEdges(-kHalfPi, kHalfPi, 8, &phiEdges);
        quadrature::panelRule(thetaEdges, &theta, &thetaWeight);
        quadrature::panelRule(phiEdges, &phi, &phiWeight);
        double sum = 0, weightSum = 0;
        for (size_t a = 0; a < theta.size(); ++a) {
            const double w =
                thetaWeight[a] * peak().eval(theta[a], -thetaI) * sqr(std::cos(theta[a]));
            for (size_t b = 0; b < phi.size(); ++b) {
                sum += w * phiWeight[b] *
                       model.rLobe().masking(wi, frame_.direction(theta[a], phi[b]));
                weightSum += w * phiWeight[b];
            }
        }
        peakMasking_[node] = weightSum > 0 ? sum / weightSum : 1.0;
    });
}

const LongitudinalGaussian& TabulatedYarnSampler::peak() const {
    return model_->rLobe().fiber().longitudinalR();
}

size_t TabulatedYarnSampler::memoryBytes() const {
    auto bytes = [](const auto& v) { return v.size() * sizeof(v[0]); };
    return sizeof(*this) + table_.bytes() + bytes(peakMasking_) + bytes(tableEnergyM_) +
           bytes(tableEnergyR_);
}

void TabulatedYarnSampler::prepare(const SurfaceFiberAngles& surface, YarnIncident& in) const {
    // The mixture's weights from the energies of its parts.
    const double pT = in.pT;
    in.table = table_.layout(std::clamp(surface.local.x, -1.0, 1.0), surface.angles.theta,
                             surface.phi);
    double peak = 0;
    if (hasReflection_) {
        // theta_i and F(theta_i) of q_R: the R lobe's fiber state has both.
        in.thetaI = in.fiber.angles.theta;
        peak = 0.5 * (1.0 - pT) * (in.fiber.fresnel * in.rScale).average() *
               table_.blend(in.table, peakMasking_);
    }
    // The table's M term, and its R term (the fiber's TT lobe inside S_R) per unit 1 - P(T).
    const double restR = (1.0 - pT) * table_.blend(in.table, tableEnergyR_);
    const double rest = table_.blend(in.table, tableEnergyM_) + restR;
    const double continuous = peak + rest;
    // q_R keeps a share wherever S_R may be positive, the table wherever S_M may be.
    in.pickR = hasReflection_ ? std::clamp(continuous > 0 ? peak / continuous : 0.5, kMinimumShare,
                                           1.0 - kMinimumShare)
                              : 0.0;
    in.pickT = pT > 0 ? std::min(pT / (pT + continuous), 1.0 - kMinimumShare) : 0.0;
}

double TabulatedYarnSampler::pdf(const YarnIncident& in, const Vec3& wo,
                                 const FiberBcsdf::Angles& out) const {
    double d = 0;
    if (in.pickR > 0 && wo.z > 0)
        d += in.pickR * peak().eval(out.theta, -in.thetaI) * out.cosTheta * kInvPi;
    if (in.pickR < 1) d += (1.0 - in.pickR) * table_.pdf(in.table, wo);
    return (1.0 - in.pickT) * d;
}

YarnDirectionSample TabulatedYarnSampler::sample(const YarnIncident& in, const BsdfSampleInput& u,
                                                 Rng& rng) const {
    // The rest of u[0], rescaled to [0, 1), picks q_R or the table, then the table's node.
    const double uPart = std::clamp((u[0] - in.pickT) / (1.0 - in.pickT), 0.0, kOneMinusEpsilon);
    if (uPart < in.pickR) {
        const double thetaO = peak().sample(-in.thetaI, u[1], rng);
        return {frame_.direction(thetaO, kPi * (u[2] - 0.5)), kYarnLobeR};
    }
    const double uNode = std::clamp((uPart - in.pickR) / (1.0 - in.pickR), 0.0, kOneMinusEpsilon);
    return {table_.sample(in.table, uNode, u[1], u[2]), kYarnLobeM};
}

YarnLobeProbabilities TabulatedYarnSampler::lobeProbabilities(const YarnIncident& in) const {
    const double continuous = 1.0 - in.pickT;
    return {in.pickT, continuous * in.pickR, continuous * (1.0 - in.pickR)};
}

}  // namespace weft
