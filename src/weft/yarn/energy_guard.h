// weft/yarn/energy_guard.h — keeps a fitted yarn model from reflecting more
// than it receives (yarn_evaluator.h; docs/yarn.md gives measured values).
//
// A fitted M network can overshoot, so that P(T|wi) + E_R(wi) + E_M(wi) > 1
// for some wi (E: the integral over wo; measured on real fits, mostly near
// grazing incidence and for nearly lossless channels such as gabardine's red).
// In a path tracer such a BSDF adds energy at every bounce. Since R <= (1 -
// P(T)) times the fiber albedo, P(T) + E_R <= 1 without an energy
// calibration, so the guard scales S_M, per channel, by
//   s(wi) = min(1, (1 - P(T|wi) - E_R(wi)) / E_M(wi));
// should a calibration push E_R above 1 - P(T), R is scaled down to it and M
// to 0. P(T|wi) and the fiber albedo a_f = F + (1 - F) C_TT at wi (in the
// surface fiber frame), which carry the sharp features, are exact at eval
// time; two tables, computed at construction by Gauss-Legendre quadrature (in
// parallel) and interpolated (bilinearly; cubic across the rows of E_M), give
// the rest:
//   E_M on a kTheta x kPhi grid of the yarn frame's polar angle (crowded
//       towards grazing incidence, where M changes fastest: polarAngle(a) =
//       90 (1 - (1 - a/23)^2) degrees; cubic across rows) and azimuth (every
//       7.5 degrees);
//   E_R / ((1 - P(T)) a_f), the part of eq. 8 left by masking and the half
//       cone, on a kFiber x kFiber grid of the surface-fiber longitudinal
//       angle and azimuth from n (fiberAngle: uniform in [-90, 90] degrees),
//       where it is smooth.
// At the nodes the guarded albedo is 1 up to the quadrature error; between
// them it is as good as the interpolation. Only cells of the M table next to a
// node whose albedo exceeds kThreshold are guarded; elsewhere s = 1 after one
// table lookup, and when there is no such node the guard is off altogether.
// Where the model conserves energy s = 1 and eval is the model's own value.
// Ablated models run it with E_R = 0. `weft yarn check` reports the raw
// model's albedo against the RDM, since that is what the fit must get right.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "weft/core/rgb.h"
#include "weft/core/vec.h"
#include "weft/fiber/fiber_bcsdf.h"
#include "weft/yarn/energy_calibration.h"
#include "weft/yarn/yarn_incident.h"

namespace weft {

class YarnEvaluator;

class EnergyGuard {
  public:
    // The tables' nodes. M table node (a, b), a < kTheta, b < kPhi: yarn-frame
    // polar angle polarAngle(a), azimuth -pi + 2 pi b / kPhi. R table node
    // (a, b), both < kFiber: surface-fiber angles fiberAngle(a), fiberAngle(b),
    // i.e. the local direction (sin theta~, cos theta~ sin phi~, cos theta~ cos phi~).
    static constexpr int kTheta = 24;
    static constexpr int kPhi = 48;
    static constexpr int kFiber = 24;
    static constexpr double kThreshold = 0.98;
    static double polarAngle(int index);  // pi/2 (1 - (1 - index / 23)^2)
    static double fiberAngle(int index);  // -pi/2 + pi index / 23

    // Off: every factor is 1.
    EnergyGuard() = default;
    // Integrates the model's S_R and S_M (no guard) at every node.
    explicit EnergyGuard(const YarnEvaluator& model);

    // Whether the guard scales S_M anywhere (false: eval is exactly the model).
    bool active() const { return active_; }

    struct Scales {
        Rgb r{1.0}, m{1.0};
    };
    // The factors on S_R and S_M at wi (upper hemisphere), given its surface
    // fiber angles, P(T|wi), the calibration there and the model's fiber.
    Scales scales(const Vec3& wi, const SurfaceFiberAngles& surface, double pT,
                  const EnergyCalibration::Scales& calibration, const FiberBcsdf& fiber) const;

    size_t memoryBytes() const;

  private:
    struct Cell {
        int a0 = 0, b0 = 0, b1 = 0;
        double fa = 0, fb = 0;
    };
    Cell cellOf(const Vec3& wi) const;
    // E_R / ((1 - P(T)) a_f) at wi, bilinear in the R table.
    Rgb keptReflectance(const SurfaceFiberAngles& surface) const;
    // E_M at a cell of the M table.
    Rgb energyM(const Cell& cell) const;

    bool active_ = false;
    // Per channel: E_R / ((1 - P(T)) a_f) before the calibration (whose scale
    // is exact at eval time), kFiber x kFiber; E_M, kTheta x kPhi.
    std::vector<Rgb> reflectance_, energyM_;
    // 1 where a cell of the M table (rows a, a + 1; columns b, b + 1) may need the guard.
    std::vector<uint8_t> guarded_;
};

}  // namespace weft
