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
// fit's energy calibration, `weft yarn check` and the energy tests; the yarn
// BSDF's energy guard builds its coarser rules with the same surfaceFiberRule.
#pragma once

#include <vector>

#include "weft/core/vec.h"
#include "weft/yarn/yarn_lobes.h"

namespace weft {

struct SphereRule {
    std::vector<Vec3> directions;  // yarn-frame unit vectors
    std::vector<double> weights;   // solid angle; they sum to 4 pi
};

// The product of the 4-point Gauss-Legendre rules on the panels between
// consecutive `thetaEdges` (longitudinal angle, sorted, within [-pi/2, pi/2])
// and `phiEdges` (azimuth from n), with the solid-angle weight cos(theta);
// nodes in theta-major order, as yarn-frame directions.
SphereRule surfaceFiberRule(const SurfaceFiberFrame& frame, const std::vector<double>& thetaEdges,
                            const std::vector<double>& phiEdges);

// The rule E_M (the M lobe's albedo) is integrated with, for any wi: 8 x 8
// panels over the sphere (the energy guard's and the exit offsets' channel
// weights, yarn_bsdf.h; 4 x 4 panels missed up to 0.36 of a shipped model's
// E_M, 16 x 16 moves it by up to 0.07 at 4 times the cost).
SphereRule mLobeSphereRule(const SurfaceFiberFrame& frame);

// `betaR`: the fiber's R lobe width (radians); wi in the yarn frame.
SphereRule surfaceFiberSphereRule(const SurfaceFiberFrame& frame, double betaR, const Vec3& wi,
                                  int refinement = 1);

}  // namespace weft
