#include "weft/gather/rdm.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "weft/core/error.h"
#include "weft/core/math.h"
#include "weft/core/sampling.h"

namespace weft {

namespace {

int angleBin(double value, double lo, double hi, int bins) {
    return std::clamp(static_cast<int>((value - lo) / (hi - lo) * bins), 0, bins - 1);
}

}  // namespace

void RdmBins::validate() const {
    const std::pair<const char*, int> counts[] = {
        {"theta_i", thetaI}, {"phi_i", phiI}, {"theta_o", thetaO}, {"phi_o", phiO}};
    for (const auto& [name, n] : counts) {
        if (n < 1 || n > 4096) {
            std::ostringstream msg;
            msg << "bins: " << name << " = " << n << " is out of range: allowed [1, 4096]";
            throw InputError(msg.str());
        }
    }
    // Two RGB maps of 8-byte accumulators must fit comfortably in memory.
    const double cells = static_cast<double>(incidentCount()) * outgoingCount();
    if (cells > 1e8) {
        std::ostringstream msg;
        msg << "bins: " << toString() << " has " << cells
            << " cells; at most 1e8 are allowed (the default 22,90,45,90 has 8.0e6)";
        throw InputError(msg.str());
    }
}

RdmBins RdmBins::parse(const std::string& text) {
    RdmBins b;
    std::istringstream in(text);
    char c1 = 0, c2 = 0, c3 = 0;
    in >> b.thetaI >> c1 >> b.phiI >> c2 >> b.thetaO >> c3 >> b.phiO;
    if (!in || c1 != ',' || c2 != ',' || c3 != ',' || !(in >> std::ws).eof())
        throw InputError("--bins \"" + text + "\": expected four integers TI,PI,TO,PO");
    b.validate();
    return b;
}

std::string RdmBins::toString() const {
    std::ostringstream s;
    s << thetaI << ',' << phiI << ',' << thetaO << ',' << phiO;
    return s.str();
}

size_t RdmBins::incidentBin(const Vec3& w) const {
    const double theta = safeAcos(w.z), phi = std::atan2(w.y, w.x);
    return static_cast<size_t>(angleBin(theta, 0, kHalfPi, thetaI)) * phiI +
           angleBin(phi, -kPi, kPi, phiI);
}

size_t RdmBins::outgoingBin(const Vec3& w) const {
    const double theta = safeAcos(w.z), phi = std::atan2(w.y, w.x);
    return static_cast<size_t>(angleBin(theta, 0, kPi, thetaO)) * phiO +
           angleBin(phi, -kPi, kPi, phiO);
}

Vec3 RdmBins::incidentCentre(size_t bin) const {
    const double theta = (static_cast<double>(bin / phiI) + 0.5) * kHalfPi / thetaI;
    const double phi = -kPi + (static_cast<double>(bin % phiI) + 0.5) * kTwoPi / phiI;
    return sphericalDirection(theta, phi);
}

Vec3 RdmBins::outgoingCentre(size_t bin) const {
    const double theta = (static_cast<double>(bin / phiO) + 0.5) * kPi / thetaO;
    const double phi = -kPi + (static_cast<double>(bin % phiO) + 0.5) * kTwoPi / phiO;
    return sphericalDirection(theta, phi);
}

double RdmBins::outgoingSolidAngle(size_t bin) const {
    const double i = static_cast<double>(bin / phiO);
    return (std::cos(i * kPi / thetaO) - std::cos((i + 1) * kPi / thetaO)) * kTwoPi / phiO;
}

double RdmBins::incidentSolidAngle(size_t bin) const {
    const double i = static_cast<double>(bin / phiI);
    return (std::cos(i * kHalfPi / thetaI) - std::cos((i + 1) * kHalfPi / thetaI)) * kTwoPi /
           phiI;
}

Vec3 RdmBins::incidentDirectionIn(size_t bin, double u1, double u2) const {
    const double t = static_cast<double>(bin / phiI), p = static_cast<double>(bin % phiI);
    const double theta0 = t * kHalfPi / thetaI, theta1 = (t + 1) * kHalfPi / thetaI;
    const double phi0 = -kPi + p * kTwoPi / phiI, phi1 = -kPi + (p + 1) * kTwoPi / phiI;
    return sampleUniformSphericalPatch(theta0, theta1, phi0, phi1, u1, u2);
}

Vec3 RdmBins::outgoingDirectionIn(size_t bin, double u1, double u2) const {
    const double t = static_cast<double>(bin / phiO), p = static_cast<double>(bin % phiO);
    const double theta0 = t * kPi / thetaO, theta1 = (t + 1) * kPi / thetaO;
    const double phi0 = -kPi + p * kTwoPi / phiO, phi1 = -kPi + (p + 1) * kTwoPi / phiO;
    return sampleUniformSphericalPatch(theta0, theta1, phi0, phi1, u1, u2);
}

}  // namespace weft
