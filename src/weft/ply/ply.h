// weft/ply/ply.h — explicit fiber geometry of one straight, twisted ply.
//
// Computes the fiber centre lines of a ply of radius R and length L along +z
// (paper section 3, eq. 1, App. A; docs/design.md sections 2 and 4):
//   - fiber radius r = R sqrt(rho / N)                          (eq. 1)
//   - N fiber centres in the cross-section z = 0: points in the disk of radius
//     R - r with pairwise distance >= 2r (so the fibers do not overlap and stay
//     inside the ply), placed by seeded random sequential placement with a
//     deterministic relaxation fallback for densities above its jamming limit;
//   - each fiber is a right-handed helix about the axis: the cross-section
//     turns counter-clockwise (seen from +z) by pi alpha z / R after axial
//     length z, so at the ply surface (radius R) fibers are tilted from the
//     axis by phi~ = atan(pi alpha) towards b = t x n (docs/design.md 2, eq. 17).
//
// Parameters (PlyParams, paper Table 3):
//   fibers   N     integer in [1, kMaxPlyFibers]
//   density  rho   fiber area fraction N r^2 / R^2, in (0, 1)
//   twist    alpha twist factor, finite and >= 0 (0: straight fibers)
// and for generatePly: radius R > 0, length L > 0 (both finite), seed (any).
//
// Feasibility: packings that are certainly impossible (more points than the
// Folkman-Graham / Oler bound allows in the disk) are rejected at once;
// otherwise placement either succeeds or throws InputError naming N and rho,
// after a bounded amount of work (well under a second for N ~ 2000). Results
// depend only on the inputs (no clocks, no threads). Random placement works
// reliably up to a density of about 0.7.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "weft/core/vec.h"

namespace weft {

// Upper bound on N accepted by PlyParams::validate (memory and time guard).
inline constexpr int kMaxPlyFibers = 1000000;

// Fiber geometry parameters of a ply (paper eq. 1, Table 3).
struct PlyParams {
    int fibers = 0;      // N >= 1
    double density = 0;  // rho in (0, 1): fiber area fraction N r^2 / R^2
    double twist = 0;    // alpha >= 0 (finite): rotation pi alpha s / R after axial length s

    // Throws InputError naming the field and its allowed range.
    void validate() const;
};

// A generated ply: fiber centres at z = 0 and the helices through them.
struct PlyGeometry {
    PlyParams params;
    double radius = 1;       // ply radius R > 0
    double length = 0;       // L > 0; the axis is +z from z = 0 to z = L
    double fiberRadius = 0;  // r = R sqrt(rho / N)
    uint64_t seed = 0;
    std::vector<std::array<double, 2>> centres;  // fiber centres (x, y) at z = 0

    // k = pi alpha / R: rotation of the cross-section in radians per unit length.
    double twistRate() const;
    // Point on fiber i's centre line at height z: centre i rotated by k z about
    // +z (right-handed: counter-clockwise seen from +z).
    Vec3 fiberCentre(int i, double z) const;
    // Unit tangent of fiber i's centre line at height z (positive z component).
    Vec3 fiberTangent(int i, double z) const;
    // Axial length of one revolution, 2R / alpha (infinity when alpha == 0).
    double twistPeriod() const;
    // Centre lines as polylines (one per fiber, same z samples for all):
    // uniformly spaced in z from exactly 0 to exactly L, with at least
    // pointsPerTwist (>= 16) points per twist period and no segment longer than
    // 2R along the axis (this bounds straight or nearly straight fibers).
    // Throws InputError if pointsPerTwist < 16 or the result would exceed
    // kMaxPlyPolylinePoints points in total.
    std::vector<std::vector<Vec3>> polylines(int pointsPerTwist = 32) const;
};

// Upper bound on the total number of points polylines() will produce.
inline constexpr int64_t kMaxPlyPolylinePoints = int64_t{1} << 26;

// Validates the inputs, places the fiber centres (deterministic for a given
// seed) and returns the ply. Throws InputError on invalid parameters or when
// the N fibers cannot be packed.
PlyGeometry generatePly(const PlyParams& params, double radius, double length, uint64_t seed);

}  // namespace weft
