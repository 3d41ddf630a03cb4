// weft/yarn/packed_calibration.h — EnergyCalibration::scales in one SIMD pass,
// for the yarn BSDF's per-vertex prepare().
//
// EnergyCalibration::scales (energy_calibration.h) is six dot products of
// (degree + 1)^2 coefficients with the basis at wi, then six exp: at degree
// 8 (the shipped models) 486 multiply-adds and 6 libm calls, a quarter of
// what prepare() cost. PackedCalibration stores the coefficients term-major,
// eight lanes per term (R red, green, blue, M red, green, blue, two zeros),
// so that one basis value multiplies all six rows at once, and computes the
// clamp and exp of all six lanes in the same vectors (Highway, dynamic
// dispatch as in fixed_mlp.cpp; hwy/contrib/math's Exp), in eight partial
// sums per lane. The sums' order and rounding and Highway's exp differ from
// the scalar reference's, so the two agree to a few ulp
// (packed_calibration_test holds them within 1e-13 relative for every
// instruction set the CPU runs; every kernel with FMA gives the same bits).
// EnergyCalibration::scales stays the reference, which the fit and the
// model's checks use.
#pragma once

#include <string>
#include <vector>

#include "weft/core/vec.h"
#include "weft/yarn/energy_calibration.h"

namespace weft {

// The compiled kernel of one instruction set (packed_calibration.cpp):
// out[0..8) = exp(clamp(sum_k coefficients[8 k + lane] basis[k])) for
// `terms` terms.
struct PackedCalibrationKernel {
    static constexpr int kLanes = 8;
    void (*scales)(const double* coefficients, const double* basis, int terms,
                   double* out) = nullptr;
    const char* target = "";
};

class PackedCalibration {
  public:
    // The kernel of the best instruction set this CPU runs (or `kernel`).
    explicit PackedCalibration(const EnergyCalibration& calibration = {});
    PackedCalibration(const EnergyCalibration& calibration, const PackedCalibrationKernel& kernel);

    bool empty() const { return degree_ < 0; }
    // EnergyCalibration::scales(wi), up to rounding.
    EnergyCalibration::Scales scales(const Vec3& wi) const;
    const char* target() const { return kernel_.target; }

  private:
    int degree_ = -1, terms_ = 0;
    std::vector<double> coefficients_;  // terms_ x kLanes, term-major
    PackedCalibrationKernel kernel_;
};

// Every compiled kernel this CPU runs, best first (for the tests).
std::vector<PackedCalibrationKernel> packedCalibrationKernels();

}  // namespace weft
