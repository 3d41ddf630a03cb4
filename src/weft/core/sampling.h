// weft/core/sampling.h — direction samplers and their densities, in twins.
//
// As pbrt-v4's util/sampling.h: every sampleX sits beside xPdf, the
// solid-angle density of the directions it returns, and every stage that
// samples these distributions calls them (pbrt-v4 style: sampling twins). The
// samplers map u1, u2 uniform in [0, 1) to unit vectors in a local frame
// whose +z is the pole; each documents its mapping, which callers rely on
// for reproducible results (the RDM gather, the lights), so a mapping is
// never changed in place.
#pragma once

#include <cmath>

#include "weft/core/math.h"
#include "weft/core/vec.h"

namespace weft {

// Uniform over the sphere: z = 1 - 2 u1, phi = 2 pi u2 (pbrt's UniformSampleSphere).
inline Vec3 sampleUniformSphere(double u1, double u2) {
    const double z = 1.0 - 2.0 * u1;
    const double r = safeSqrt(1.0 - z * z), phi = kTwoPi * u2;
    return {r * std::cos(phi), r * std::sin(phi), z};
}
constexpr double uniformSpherePdf() { return 0.25 * kInvPi; }

// Uniform over the upper hemisphere (z >= 0): z = cos theta = u1 and
// phi = 2 pi u2 - pi, in [-pi, pi) as the RDM's azimuths (gather/rdm.h);
// pbrt's phi = 2 pi u2 gives the same distribution but other directions.
inline Vec3 sampleUniformHemisphere(double u1, double u2) {
    const double cosTheta = u1;
    const double sinTheta = safeSqrt(1.0 - cosTheta * cosTheta);
    const double phi = kTwoPi * u2 - kPi;
    return {sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta};
}
constexpr double uniformHemispherePdf() { return 0.5 * kInvPi; }

// Cosine-weighted over the upper hemisphere (z >= 0) by the polar mapping:
// sin theta = sqrt(u1), z = sqrt(1 - u1), phi = 2 pi u2 (not pbrt's
// concentric-disk mapping: same distribution, other directions).
inline Vec3 sampleCosineHemisphere(double u1, double u2) {
    const double r = std::sqrt(u1), phi = kTwoPi * u2;
    const double z = safeSqrt(1.0 - u1);
    return {r * std::cos(phi), r * std::sin(phi), z};
}
// Density at a direction with z = cosTheta >= 0 (0 below the equator is the caller's test).
constexpr double cosineHemispherePdf(double cosTheta) { return cosTheta * kInvPi; }

// Uniform in solid angle over the patch theta in [theta0, theta1] (from +z,
// theta0 <= theta1 in [0, pi]), phi in [phi0, phi1]: cos theta = c0 + u1 (c1 -
// c0) with c = cos(theta), phi = phi0 + u2 (phi1 - phi0). The RDM's bins are
// such patches (gather/rdm.h).
inline Vec3 sampleUniformSphericalPatch(double theta0, double theta1, double phi0, double phi1,
                                        double u1, double u2) {
    const double c0 = std::cos(theta0), c1 = std::cos(theta1);
    const double cosTheta = c0 + u1 * (c1 - c0);
    const double sinTheta = safeSqrt(1.0 - cosTheta * cosTheta);
    const double phi = phi0 + u2 * (phi1 - phi0);
    return {sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta};
}
// Density inside the patch: one over its solid angle (cos theta0 - cos theta1) (phi1 - phi0).
inline double uniformSphericalPatchPdf(double theta0, double theta1, double phi0, double phi1) {
    return 1.0 / ((std::cos(theta0) - std::cos(theta1)) * (phi1 - phi0));
}

}  // namespace weft
