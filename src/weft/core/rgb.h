// weft/core/rgb.h — linear RGB triple used for BSDF values and path weights.
#pragma once

#include <array>
#include <cmath>
#include <ostream>

namespace weft {

struct Rgb {
    double r = 0, g = 0, b = 0;

    constexpr Rgb() = default;
    constexpr explicit Rgb(double v) : r(v), g(v), b(v) {}
    constexpr Rgb(double r_, double g_, double b_) : r(r_), g(g_), b(b_) {}

    constexpr double operator[](int i) const { return i == 0 ? r : (i == 1 ? g : b); }
    constexpr double& operator[](int i) { return i == 0 ? r : (i == 1 ? g : b); }
    constexpr Rgb& operator+=(const Rgb& o) { r += o.r; g += o.g; b += o.b; return *this; }
    constexpr Rgb& operator-=(const Rgb& o) { r -= o.r; g -= o.g; b -= o.b; return *this; }
    constexpr Rgb& operator*=(const Rgb& o) { r *= o.r; g *= o.g; b *= o.b; return *this; }
    constexpr Rgb& operator*=(double s) { r *= s; g *= s; b *= s; return *this; }
    constexpr bool operator==(const Rgb&) const = default;

    constexpr double average() const { return (r + g + b) / 3.0; }
    constexpr double maxComponent() const { return r > g ? (r > b ? r : b) : (g > b ? g : b); }
    constexpr bool isBlack() const { return r == 0 && g == 0 && b == 0; }
    bool isFinite() const { return std::isfinite(r) && std::isfinite(g) && std::isfinite(b); }
    constexpr std::array<double, 3> array() const { return {r, g, b}; }
};

constexpr Rgb operator+(Rgb a, const Rgb& b) { return a += b; }
constexpr Rgb operator-(Rgb a, const Rgb& b) { return a -= b; }
constexpr Rgb operator*(Rgb a, const Rgb& b) { return a *= b; }
constexpr Rgb operator*(Rgb a, double s) { return a *= s; }
constexpr Rgb operator*(double s, Rgb a) { return a *= s; }
constexpr Rgb operator/(Rgb a, double s) { return a *= (1.0 / s); }

// Luminance Y of linear Rec. 709 / sRGB primaries: the weight of a texel in
// envmap sampling (render/lights.cpp) and the grey level SSIM compares
// (eval/image_compare.cpp).
constexpr double luminance(const Rgb& c) { return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b; }

inline std::ostream& operator<<(std::ostream& os, const Rgb& c) {
    return os << '[' << c.r << ", " << c.g << ", " << c.b << ']';
}

}  // namespace weft
