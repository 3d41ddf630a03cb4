// weft/yarn/sphere_rule.h — a quadrature rule over the sphere of outgoing
// directions for the yarn BSDF's lobes, in the surface fiber frame.
//
// Product Gauss-Legendre rule in the surface fiber frame (longitudinal angle
// theta from -pi/2 to pi/2, azimuth phi from n), with the solid-angle weight
// cos(theta):
//   theta: 4-node panels of 7.5 degrees, and of beta_R / 2 within 6 beta_R of
//          the specular cone theta = -theta_i, where the R lobe (as narrow as
//          1 degree) lives;
//   phi:   16 panels of 4 nodes, with edges at phi = 0, +-pi/2 (where R and
//          pdf_R jump to zero: the surface plane) and +-pi.
// About 12,000 nodes; `refinement` divides every panel width. Used by the
// fit's energy calibration, `weft yarn check` and the energy tests.
#pragma once

#include <vector>

#include "weft/core/vec.h"
#include "weft/yarn/yarn_lobes.h"

namespace weft {

struct SphereRule {
    std::vector<Vec3> directions;  // yarn-frame unit vectors
    std::vector<double> weights;   // solid angle; they sum to 4 pi
};

// `betaR`: the fiber's R lobe width (radians); wi in the yarn frame.
SphereRule surfaceFiberSphereRule(const SurfaceFiberFrame& frame, double betaR, const Vec3& wi,
                                  int refinement = 1);

}  // namespace weft
