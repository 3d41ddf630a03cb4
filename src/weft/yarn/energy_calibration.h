// weft/yarn/energy_calibration.h — per-direction energy calibration of the R
// lobe and the M network (a weft addition to the paper's model).
//
// Why: the analytic R lobe (eq. 8 with masking) has the right shape but not
// the right energy at every incident direction (on fleece, 20-40% low near
// normal and grazing incidence, 15-30% high around 60 degrees), and the M
// network, trained on point values, drifts by 5-15% in energy near grazing
// incidence. The directional albedo is what a path tracer's brightness and
// colour after many bounces depend on, so the fit ends with one smooth scale
// per component, channel and incident direction that makes the model's
// energies match the RDM's:
//   S_R(wi, wo) <- s_R,c(wi) S_R(wi, wo),   S_M(wi, wo) <- s_M,c(wi) S_M(wi, wo)
//   log s(wi) = sum_k coefficient_k * basis_k(wi)
// with basis_k the monomials x^a y^b z^c of the (upper-hemisphere) yarn-frame
// direction with a in {0, 1} and a + b + c <= degree: a basis of the
// polynomials of that degree on the sphere, (degree + 1)^2 terms, smooth
// everywhere (no seam in azimuth, no pole at the normal). log s is clamped to
// [-log 4, log 4] so that no extrapolation can blow up. The lobe shapes, the
// sampling densities and P(T) are unchanged; only the magnitudes move.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "weft/core/rgb.h"
#include "weft/core/vec.h"

namespace weft {

struct EnergyCalibration {
    static constexpr int kMaxDegree = 12;
    static constexpr double kMaxLogScale = 1.3862943611198906;  // log 4

    int degree = -1;  // -1: no calibration (every scale is 1)
    std::array<std::vector<double>, 3> r, m;  // per channel, termCount(degree) coefficients

    bool empty() const { return degree < 0; }
    static int termCount(int degree) { return (degree + 1) * (degree + 1); }
    // Position of x^a y^b z^c (a in {0, 1}, a + b + c <= degree) in the basis.
    static int termIndex(int a, int b, int c, int degree);
    // The basis at a yarn-frame unit direction, in the order a, then b, then c.
    static void basis(const Vec3& w, int degree, double* out);

    struct Scales {
        Rgb r{1.0}, m{1.0};
    };
    // Scales at an upper-hemisphere wi (all 1 when empty()).
    Scales scales(const Vec3& wi) const;
};

// The energy calibration of a colour-conditioned model (docs/colour.md): one
// EnergyCalibration per node colour, fitted at the grey C_TT = node, and for
// any C_TT, per channel c, the coefficients of channel c interpolated
// linearly in u = sqrt(-ln C_TT,c) between the two nodes around C_TT,c
// (clamped to the first and last node). A channel's RDM depends on its own
// C_TT only (gather/colour_paths.h), so a grey node calibrates every channel
// at that value.
struct ColourCalibration {
    static constexpr int kMaxNodes = 64;
    std::vector<double> cTT;               // node colours, strictly increasing, in (0, 1]
    std::vector<EnergyCalibration> nodes;  // one per node, all of one degree

    bool empty() const { return nodes.empty(); }
    // The interpolation variable u = sqrt(-ln c).
    static double variableOf(double c);
    // InputError naming `what` unless there are 1 to kMaxNodes nodes, the node
    // colours are strictly increasing in (0, 1], and every node has the same
    // degree and 3 rows of (degree + 1)^2 coefficients for R and M.
    void validate(const std::string& what) const;
    // InputError naming `what`.c_tt[g] unless the node colours increase strictly within (0, 1].
    static void validateNodeColours(const std::vector<double>& cTT, const std::string& what);
    // The calibration of the model of colour cTT (each channel in [0, 1]).
    EnergyCalibration at(const Rgb& cTT) const;
};

}  // namespace weft
