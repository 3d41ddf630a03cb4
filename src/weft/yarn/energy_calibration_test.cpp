#include "weft/yarn/energy_calibration.h"

#include <gtest/gtest.h>

#include <cmath>

#include "weft/core/math.h"
#include "weft/core/rng.h"

namespace weft {
namespace {

// basis() holds x^a y^b z^c at termIndex(a, b, c): checked against std::pow.
TEST(EnergyCalibration, BasisTermsAreTheMonomials) {
    Rng rng(7, 1);
    for (int degree : {0, 1, 3, 6, EnergyCalibration::kMaxDegree}) {
        const double z = rng.uniform(), phi = kTwoPi * rng.uniform();
        const double s = std::sqrt(std::max(0.0, 1 - z * z));
        const Vec3 w{s * std::cos(phi), s * std::sin(phi), z};
        std::vector<double> f(static_cast<size_t>(EnergyCalibration::termCount(degree)));
        EnergyCalibration::basis(w, degree, f.data());
        int terms = 0;
        for (int a = 0; a <= std::min(degree, 1); ++a)
            for (int b = 0; a + b <= degree; ++b)
                for (int c = 0; a + b + c <= degree; ++c, ++terms)
                    EXPECT_DOUBLE_EQ(f[EnergyCalibration::termIndex(a, b, c, degree)],
                                     std::pow(w.x, a) * std::pow(w.y, b) * std::pow(w.z, c));
        EXPECT_EQ(terms, EnergyCalibration::termCount(degree));
    }
}

TEST(EnergyCalibration, EmptyIsOneAndLogScaleIsClamped) {
    EnergyCalibration cal;
    EXPECT_TRUE(cal.empty());
    EXPECT_EQ(cal.scales({0, 0, 1}).r.r, 1.0);
    cal.degree = 0;
    cal.r = {std::vector<double>{10.0}, std::vector<double>{-10.0}, std::vector<double>{0.5}};
    cal.m = {std::vector<double>{0.0}, std::vector<double>{0.0}, std::vector<double>{0.0}};
    const EnergyCalibration::Scales s = cal.scales({0.6, 0, 0.8});
    EXPECT_DOUBLE_EQ(s.r.r, 4.0);
    EXPECT_DOUBLE_EQ(s.r.g, 0.25);
    EXPECT_NEAR(s.r.b, std::exp(0.5), 1e-15);
}

}  // namespace
}  // namespace weft
