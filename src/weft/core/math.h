// weft/core/math.h — constants and scalar helpers shared by the models.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>

namespace weft {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kTwoPi = 2.0 * std::numbers::pi;
inline constexpr double kHalfPi = 0.5 * std::numbers::pi;
inline constexpr double kInvPi = std::numbers::inv_pi;
// The largest double below 1: uniform numbers are clamped to [0, this].
inline constexpr double kOneMinusEpsilon = 0x1.fffffffffffffp-1;

constexpr double radians(double deg) { return deg * (kPi / 180.0); }
constexpr double degrees(double rad) { return rad * (180.0 / kPi); }
constexpr double sqr(double x) { return x * x; }

// asin / acos / sqrt that tolerate arguments a rounding error outside their domain.
inline double safeAsin(double x) { return std::asin(std::clamp(x, -1.0, 1.0)); }
inline double safeAcos(double x) { return std::acos(std::clamp(x, -1.0, 1.0)); }
inline double safeSqrt(double x) { return std::sqrt(std::max(0.0, x)); }

// Wraps an angle to [-pi, pi).
inline double wrapAngle(double a) {
    a = std::fmod(a + kPi, kTwoPi);
    if (a < 0) a += kTwoPi;
    return a - kPi;
}

// Inverse error function to double precision (Giles 2010, double-precision
// polynomials). erfInv(+-1) = +-inf.
double erfInv(double y);

// exp(-x) I0(x): the exponentially scaled modified Bessel function of order 0,
// finite for every x >= 0 (I0 itself overflows above x ~ 700).
double besselI0Scaled(double x);

}  // namespace weft
