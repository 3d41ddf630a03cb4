#include "weft/yarn/sphere_rule.h"

#include <algorithm>
#include <cmath>

#include "weft/core/math.h"
#include "weft/core/quadrature.h"

namespace weft {

using quadrature::panelRule;
using quadrature::uniformEdges;

SphereRule surfaceFiberSphereRule(const SurfaceFiberFrame& frame, double betaR, const Vec3& wi,
                                  int refinement) {
    refinement = std::max(1, refinement);
    const double thetaI = safeAsin(frame.toLocal(wi).x);

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

}  // namespace weft
