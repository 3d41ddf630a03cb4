#include "weft/yarn/sphere_rule.h"

#include <algorithm>
#include <cmath>

#include "weft/core/math.h"
#include "weft/core/quadrature.h"

namespace weft {

using quadrature::panelRule;
using quadrature::uniformEdges;

SphereRule surfaceFiberRule(const SurfaceFiberFrame& frame, const std::vector<double>& thetaEdges,
                            const std::vector<double>& phiEdges) {
    std::vector<double> thetaX, thetaW, phiX, phiW;
    panelRule(thetaEdges, &thetaX, &thetaW);
    panelRule(phiEdges, &phiX, &phiW);
    SphereRule rule;
    rule.directions.reserve(thetaX.size() * phiX.size());
    rule.weights.reserve(thetaX.size() * phiX.size());
    for (size_t a = 0; a < thetaX.size(); ++a) {
        const double cosTheta = std::cos(thetaX[a]);
        for (size_t b = 0; b < phiX.size(); ++b) {
            rule.directions.push_back(frame.direction(thetaX[a], phiX[b]));
            rule.weights.push_back(thetaW[a] * phiW[b] * cosTheta);
        }
    }
    return rule;
}

SphereRule mLobeSphereRule(const SurfaceFiberFrame& frame) {
    std::vector<double> thetaEdges, phiEdges;
    uniformEdges(-kHalfPi, kHalfPi, 8, &thetaEdges);
    uniformEdges(-kPi, kPi, 8, &phiEdges);
    return surfaceFiberRule(frame, thetaEdges, phiEdges);
}

SphereRule surfaceFiberSphereRule(const SurfaceFiberFrame& frame, double betaR, const Vec3& wi,
                                  int refinement) {
    refinement = std::max(1, refinement);
    const double thetaI = frame.longitudinalAngle(wi);
    std::vector<double> thetaEdges;
    uniformEdges(-kHalfPi, kHalfPi, 24 * refinement, &thetaEdges);
    const double centre = -thetaI, halfWidth = 6 * betaR;
    uniformEdges(std::max(-kHalfPi, centre - halfWidth), std::min(kHalfPi, centre + halfWidth),
                 24 * refinement, &thetaEdges);
    std::sort(thetaEdges.begin(), thetaEdges.end());
    std::vector<double> phiEdges;
    uniformEdges(-kPi, kPi, 16 * refinement, &phiEdges);  // includes +-pi/2 and 0
    return surfaceFiberRule(frame, thetaEdges, phiEdges);
}

}  // namespace weft
