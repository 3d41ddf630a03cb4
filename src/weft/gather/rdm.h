// weft/gather/rdm.h — binning of the reflectance distribution map (RDM).
//
// docs/design.md 2: RDM angles are spherical angles in the yarn (entry) frame
// (t, b, n): theta is the polar angle from n, phi the azimuth from t towards
// b in [-pi, pi). Incident directions cover the upper hemisphere (theta_i in
// [0, pi/2]), outgoing ones the whole sphere (theta_o in [0, pi]); bins are
// uniform in angle. The solid angle of an outgoing bin is
// (cos a - cos b) dphi. Default resolution 22 x 90 x 45 x 90 (the paper's).
#pragma once

#include <cstddef>
#include <string>

#include "weft/core/vec.h"

namespace weft {

struct RdmBins {
    int thetaI = 22, phiI = 90, thetaO = 45, phiO = 90;

    // InputError naming the offending count (each in [1, 4096], total size bounded).
    void validate() const;
    // Parses "TI,PI,TO,PO".
    static RdmBins parse(const std::string& text);
    std::string toString() const;

    size_t incidentCount() const { return static_cast<size_t>(thetaI) * phiI; }
    size_t outgoingCount() const { return static_cast<size_t>(thetaO) * phiO; }

    // Bin of a direction given in local (t, b, n) coordinates; incident
    // directions are clamped to the upper hemisphere.
    size_t incidentBin(const Vec3& local) const;
    size_t outgoingBin(const Vec3& local) const;

    // Centre direction of an incident / outgoing bin, and the outgoing solid angle.
    Vec3 incidentCentre(size_t bin) const;
    Vec3 outgoingCentre(size_t bin) const;
    double outgoingSolidAngle(size_t bin) const;
    // Solid angle of an incident bin (theta_i in [0, pi/2]).
    double incidentSolidAngle(size_t bin) const;
    // A direction inside a bin, uniform in solid angle for uniform (u1, u2) in [0, 1)^2.
    Vec3 incidentDirectionIn(size_t bin, double u1, double u2) const;
    Vec3 outgoingDirectionIn(size_t bin, double u1, double u2) const;
};

}  // namespace weft
