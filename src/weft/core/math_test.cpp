#include "weft/core/math.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace weft {
namespace {

// Reference inverse in long double (64-bit mantissa on x86): Newton on erfl
// for small |y|, on erfcl(x) = 1 - |y| near +-1 where 1 - |y| is exact.
long double erfInvReference(double y) {
    const long double a = std::fabs(static_cast<long double>(y));
    const bool tail = a > 0.5L;
    const long double target = tail ? 1.0L - a : a;
    long double x = tail ? std::sqrt(-std::log(target)) : a;
    for (int i = 0; i < 60; ++i) {
        const long double f = tail ? std::erfc(x) - target : std::erf(x) - target;
        const long double df = 2.0L / std::sqrt(3.14159265358979323846264338327950288L) *
                               std::exp(-x * x) * (tail ? -1.0L : 1.0L);
        x -= f / df;
    }
    return y < 0 ? -x : x;
}

TEST(ErfInv, SpecialValues) {
    EXPECT_EQ(erfInv(0.0), 0.0);
    EXPECT_EQ(erfInv(1.0), std::numeric_limits<double>::infinity());
    EXPECT_EQ(erfInv(-1.0), -std::numeric_limits<double>::infinity());
    EXPECT_TRUE(std::isnan(erfInv(1.5)));
    EXPECT_TRUE(std::isnan(erfInv(-1.5)));
    EXPECT_TRUE(std::isnan(erfInv(std::numeric_limits<double>::quiet_NaN())));
}

TEST(ErfInv, RoundTripThroughErf) {
    // erf(x) rounds to a double y, and every x' with erf(x') == y is an
    // equally good inverse: for |x| > ~3 that rounding alone moves x by more
    // than 1e-13 relative (by 1e-4 at 5.5). So the bound is 1e-13 relative
    // plus the change in x that one ulp of y makes, ulp(y) / erf'(x).
    for (int i = -55000; i <= 55000; ++i) {
        const double x = i * 1e-4;
        const double y = std::erf(x);
        const double ulp = std::nextafter(std::fabs(y), 2.0) - std::fabs(y);
        const double slope = 2.0 / std::sqrt(kPi) * std::exp(-x * x);
        const double tol = 1e-13 * std::fabs(x) + ulp / slope;
        ASSERT_NEAR(erfInv(y), x, tol) << "x = " << x;
    }
}

TEST(ErfInv, MatchesHighPrecisionInverse) {
    // Relative error 1e-13 against the long double inverse of the same y,
    // including y within 1e-12 and 1e-15 of +-1.
    std::vector<double> ys;
    for (int i = -1000; i <= 1000; ++i) ys.push_back(i * 0.000999);
    for (double d = 1e-1; d > 1e-16; d *= 0.3) {
        ys.push_back(1 - d);
        ys.push_back(-(1 - d));
    }
    ys.push_back(1 - 1e-12);
    ys.push_back(-1 + 1e-12);
    ys.push_back(std::nextafter(1.0, 0.0));
    ys.push_back(1e-300);
    ys.push_back(-1e-20);
    for (double y : ys) {
        if (y == 0) continue;
        const long double ref = erfInvReference(y);
        const double got = erfInv(y);
        EXPECT_LE(std::fabs((got - ref) / ref), 1e-13) << "y = " << y;
    }
    EXPECT_NEAR(erfInv(1 - 1e-12), 5.042031898572696, 1e-13 * 5.05);
}

TEST(ErfInv, IsOdd) {
    for (double y : {1e-10, 0.1, 0.5, 0.9, 0.999999, 1 - 1e-12})
        EXPECT_EQ(erfInv(-y), -erfInv(y)) << y;
}

TEST(BesselI0Scaled, MatchesStdUpTo600) {
    for (double x = 0; x <= 600; x += 0.173) {
        const double ref = std::cyl_bessel_i(0.0, x) * std::exp(-x);
        EXPECT_NEAR(besselI0Scaled(x), ref, 1e-14 * ref) << "x = " << x;
        EXPECT_EQ(besselI0Scaled(-x), besselI0Scaled(x));
    }
    for (double x : {499.0, 500.0, 500.5, 550.0, 600.0}) {
        const double ref = std::cyl_bessel_i(0.0, x) * std::exp(-x);
        EXPECT_NEAR(besselI0Scaled(x), ref, 1e-14 * ref) << "x = " << x;
    }
    EXPECT_EQ(besselI0Scaled(0.0), 1.0);
}

TEST(BesselI0Scaled, ContinuousAtSeriesSwitch) {
    const double below = besselI0Scaled(std::nextafter(500.0, 0.0));
    const double at = besselI0Scaled(500.0);
    EXPECT_NEAR(below, at, 1e-14 * at);
}

TEST(BesselI0Scaled, AsymptoticForLargeX) {
    const double x = 1e4;
    // Three terms of A&S 9.7.1: the next term, 225/(3072 x^3) ~ 7e-14
    // relative, is 3e-16 absolute, so this matches to 1e-15 absolute.
    const double three = 1 / std::sqrt(2 * kPi * x) * (1 + 1 / (8 * x) + 9 / (128 * x * x));
    EXPECT_NEAR(besselI0Scaled(x), three, 1e-15);
    const double four = 1 / std::sqrt(2 * kPi * x) *
                        (1 + 1 / (8 * x) + 9 / (128 * x * x) + 225 / (3072 * x * x * x));
    EXPECT_NEAR(besselI0Scaled(x), four, 1e-15 * four);
    EXPECT_TRUE(std::isfinite(besselI0Scaled(1e300)));
    EXPECT_GT(besselI0Scaled(1e300), 0.0);
}

}  // namespace
}  // namespace weft
