// weft/yarn/yarn_integrals.h — integrals of the yarn BSDF over outgoing directions.
//
// For one incident direction wi, by a product Gauss-Legendre rule over the
// sphere in the surface fiber frame (longitudinal angle theta from -pi/2 to
// pi/2, azimuth phi from n), with the solid-angle weight cos(theta):
//   theta: 4-node panels of 7.5 degrees, and of beta_R / 2 within 6 beta_R of
//          the specular cone theta = -theta_i, where the R lobe (as narrow as
//          1 degree) lives;
//   phi:   16 panels of 4 nodes, with edges at phi = 0, +-pi/2 (where R and
//          pdf_R jump to zero: the surface plane) and +-pi.
// About 12,000 nodes; `refinement` divides every panel width (the tests check
// that 1 agrees with 3). Used by `weft yarn check` and the energy tests.
#pragma once

#include <vector>

#include "weft/core/rgb.h"
#include "weft/core/vec.h"
#include "weft/yarn/yarn_bsdf.h"

namespace weft {

struct DirectionalIntegrals {
    double pT = 0;  // P(T | wi): the delta lobe's share
    Rgb r, m;       // integrals of S_R and S_M (as the BSDF evaluates them) over the sphere
    Rgb albedo() const { return r + m + Rgb(pT); }

    // Variance proxies for the continuous part, f = channel mean of R + M:
    // relative second moments  V_p = integral of f^2 / p  /  (integral of f)^2
    // (the mean squared weight f/p of an estimator of the integral of f drawing wo
    // from p, in units of the squared integral; 1 is a perfect sampler).
    double secondMomentYarn = 0;     // p = pdf() / (1 - P(T|wi)): sample()'s continuous part
    double secondMomentUniform = 0;  // p = 1 / (4 pi)
    double secondMomentCosine = 0;   // p = |cos theta_o| / (2 pi): cosine-weighted on each
                                     // hemisphere, each picked with probability 1/2
};

DirectionalIntegrals integrateDirections(const YarnBsdf& bsdf, const Vec3& wi, int refinement = 1);

// The nodes of that rule (yarn-frame directions) and their weights, for tests.
struct SphereRule {
    std::vector<Vec3> directions;
    std::vector<double> weights;
};
SphereRule yarnSphereRule(const YarnBsdf& bsdf, const Vec3& wi, int refinement = 1);

}  // namespace weft
