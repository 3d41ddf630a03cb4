#include "weft/yarn/yarn_integrals.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "weft/core/math.h"
#include "weft/yarn/quadrature.h"

namespace weft {

using quadrature::panelRule;
using quadrature::uniformEdges;

SphereRule yarnSphereRule(const YarnBsdf& bsdf, const Vec3& wi, int refinement) {
    refinement = std::max(1, refinement);
    const SurfaceFiberFrame& frame = bsdf.surfaceFiberFrame();
    const double thetaI = safeAsin(frame.toLocal(wi).x);
    const double betaR = radians(bsdf.rLobe().fiber().params().betaRDeg);

    std::vector<double> thetaEdges;
    uniformEdges(-kHalfPi, kHalfPi, 24 * refinement, &thetaEdges);
    const double centre = -thetaI, halfWidth = 6 * betaR;
    uniformEdges(std::max(-kHalfPi, centre - halfWidth), std::min(kHalfPi, centre + halfWidth),
                 24 * refinement, &thetaEdges);
    std::sort(thetaEdges.begin(), thetaEdges.end());
    std::vector<double> thetaX, thetaW;
    panelRule(thetaEdges, &thetaX, &thetaW);

    std::vector<double> phiEdges;
    uniformEdges(-kPi, kPi, 16 * refinement, &phiEdges);  // includes +-pi/2 and 0
    std::vector<double> phiX, phiW;
    panelRule(phiEdges, &phiX, &phiW);

    SphereRule rule;
    rule.directions.reserve(thetaX.size() * phiX.size());
    rule.weights.reserve(thetaX.size() * phiX.size());
    for (size_t a = 0; a < thetaX.size(); ++a) {
        const double cosTheta = std::cos(thetaX[a]), sinTheta = std::sin(thetaX[a]);
        for (size_t b = 0; b < phiX.size(); ++b) {
            const Vec3 local{sinTheta, cosTheta * std::sin(phiX[b]), cosTheta * std::cos(phiX[b])};
            rule.directions.push_back(frame.fromLocal(local));
            rule.weights.push_back(thetaW[a] * phiW[b] * cosTheta);
        }
    }
    return rule;
}

DirectionalIntegrals integrateDirections(const YarnBsdf& bsdf, const Vec3& wi, int refinement) {
    const SphereRule rule = yarnSphereRule(bsdf, wi, refinement);
    DirectionalIntegrals out;
    out.pT = bsdf.transmission(wi);
    const double continuousShare = 1.0 - out.pT;
    double integral = 0, yarn = 0, uniform = 0, cosine = 0;
    for (size_t k = 0; k < rule.directions.size(); ++k) {
        const Vec3& wo = rule.directions[k];
        const double w = rule.weights[k];
        const YarnBsdf::Components c = bsdf.components(wi, wo);
        out.r += c.r * w;
        out.m += c.m * w;
        const double f = (c.r + c.m).average();
        if (f == 0) continue;
        integral += f * w;
        const double pYarn = continuousShare > 0 ? bsdf.pdf(wi, wo) / continuousShare : 0.0;
        yarn += pYarn > 0 ? f * f / pYarn * w : std::numeric_limits<double>::infinity();
        uniform += f * f * (4 * kPi) * w;
        const double pCosine = std::fabs(wo.z) / kTwoPi;
        cosine += pCosine > 0 ? f * f / pCosine * w : std::numeric_limits<double>::infinity();
    }
    const double squared = integral * integral;
    if (squared > 0) {
        out.secondMomentYarn = yarn / squared;
        out.secondMomentUniform = uniform / squared;
        out.secondMomentCosine = cosine / squared;
    }
    return out;
}

}  // namespace weft
