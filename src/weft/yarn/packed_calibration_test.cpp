#include "weft/yarn/packed_calibration.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "weft/core/math.h"
#include "weft/core/rng.h"

namespace weft {
namespace {

EnergyCalibration randomCalibration(int degree, double spread, Rng& rng) {
    EnergyCalibration cal;
    cal.degree = degree;
    const size_t terms = static_cast<size_t>(EnergyCalibration::termCount(degree));
    for (int c = 0; c < 3; ++c) {
        cal.r[c].resize(terms);
        cal.m[c].resize(terms);
        for (size_t k = 0; k < terms; ++k) {
            cal.r[c][k] = spread * (2 * rng.uniform() - 1);
            cal.m[c][k] = spread * (2 * rng.uniform() - 1);
        }
    }
    return cal;
}

// exp(clamp(sum_k c_k x^a y^b z^c)) term by term with std::pow: the definition
// in energy_calibration.h, independent of basis() and of the packed layout.
double byDefinition(const std::vector<double>& c, int degree, const Vec3& w) {
    double sum = 0;
    for (int a = 0; a <= std::min(degree, 1); ++a)
        for (int b = 0; a + b <= degree; ++b)
            for (int e = 0; a + b + e <= degree; ++e)
                sum += c[EnergyCalibration::termIndex(a, b, e, degree)] * std::pow(w.x, a) *
                       std::pow(w.y, b) * std::pow(w.z, e);
    return std::exp(
        std::clamp(sum, -EnergyCalibration::kMaxLogScale, EnergyCalibration::kMaxLogScale));
}

// Every kernel the CPU runs gives the calibration's scales for every degree,
// inside and at the clamp (spread 2: many log scales beyond log 4).
TEST(PackedCalibration, EveryKernelMatchesTheDefinition) {
    Rng rng(11, 5);
    const auto kernels = packedCalibrationKernels();
    ASSERT_FALSE(kernels.empty());
    for (const PackedCalibrationKernel& kernel : kernels)
        for (int degree : {0, 1, 2, 5, 8, EnergyCalibration::kMaxDegree})
            for (double spread : {0.05, 0.4, 2.0}) {
                const EnergyCalibration cal = randomCalibration(degree, spread, rng);
                const PackedCalibration packed(cal, kernel);
                for (int trial = 0; trial < 50; ++trial) {
                    const double z = rng.uniform(), phi = kTwoPi * rng.uniform();
                    const double s = std::sqrt(std::max(0.0, 1 - z * z));
                    const Vec3 w{s * std::cos(phi), s * std::sin(phi), z};
                    const EnergyCalibration::Scales fast = packed.scales(w),
                                                    reference = cal.scales(w);
                    for (int c = 0; c < 3; ++c) {
                        const double r = byDefinition(cal.r[c], degree, w),
                                     m = byDefinition(cal.m[c], degree, w);
                        ASSERT_NEAR(fast.r[c], r, 1e-12 * r) << kernel.target << " degree " << degree;
                        ASSERT_NEAR(fast.m[c], m, 1e-12 * m) << kernel.target << " degree " << degree;
                        ASSERT_NEAR(fast.r[c], reference.r[c], 1e-13 * r) << kernel.target;
                        ASSERT_NEAR(fast.m[c], reference.m[c], 1e-13 * m) << kernel.target;
                    }
                }
            }
}

TEST(PackedCalibration, EmptyIsOne) {
    const PackedCalibration packed{EnergyCalibration{}};
    EXPECT_TRUE(packed.empty());
    const EnergyCalibration::Scales s = packed.scales({0.3, 0.4, std::sqrt(0.75)});
    for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(s.r[c], 1.0);
        EXPECT_EQ(s.m[c], 1.0);
    }
}

}  // namespace
}  // namespace weft
