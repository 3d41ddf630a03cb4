// weft/core/vec.h — small value types for directions and frames.
//
// Vec3 is a plain 3-vector of doubles; Frame is an orthonormal basis with
// toLocal/fromLocal. Everything is double precision: the fiber and yarn models
// are evaluated far from the edge of float accuracy (grazing angles, narrow
// Gaussians) and the CPU cost of doubles is negligible next to ray tracing.
#pragma once

#include <cmath>
#include <ostream>

namespace weft {

struct Vec3 {
    double x = 0, y = 0, z = 0;

    constexpr Vec3() = default;
    constexpr Vec3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}

    constexpr double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    constexpr Vec3 operator-() const { return {-x, -y, -z}; }
    constexpr Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
    constexpr Vec3& operator-=(const Vec3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
    constexpr Vec3& operator*=(double s) { x *= s; y *= s; z *= s; return *this; }
    constexpr bool operator==(const Vec3&) const = default;
};

constexpr Vec3 operator+(Vec3 a, const Vec3& b) { return a += b; }
constexpr Vec3 operator-(Vec3 a, const Vec3& b) { return a -= b; }
constexpr Vec3 operator*(Vec3 a, double s) { return a *= s; }
constexpr Vec3 operator*(double s, Vec3 a) { return a *= s; }
constexpr Vec3 operator/(Vec3 a, double s) { return a *= (1.0 / s); }

constexpr double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length(const Vec3& a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalize(const Vec3& a) { return a / length(a); }
// The unit vector along any finite non-zero v, however long or short: scaled
// by its largest component first (so the squared length neither overflows nor
// underflows), dividing each component, since 1 / s overflows for a
// sub-normal s. v must be finite and non-zero.
inline Vec3 normalizeAnyLength(const Vec3& v) {
    const double largest = std::fmax(std::fabs(v.x), std::fmax(std::fabs(v.y), std::fabs(v.z)));
    return normalize(Vec3{v.x / largest, v.y / largest, v.z / largest});
}
inline bool isFinite(const Vec3& a) {
    return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}

inline std::ostream& operator<<(std::ostream& os, const Vec3& v) {
    return os << '(' << v.x << ", " << v.y << ", " << v.z << ')';
}

// Builds two unit vectors orthogonal to the unit vector n (Duff et al. 2017,
// "Building an Orthonormal Basis, Revisited"), so that (s, t, n) is right-handed.
inline void coordinateSystem(const Vec3& n, Vec3* s, Vec3* t) {
    const double sign = std::copysign(1.0, n.z);
    const double a = -1.0 / (sign + n.z);
    const double b = n.x * n.y * a;
    *s = {1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x};
    *t = {b, sign + n.y * n.y * a, -n.y};
}

// Orthonormal frame; local coordinates of w are (w.s, w.t, w.n).
struct Frame {
    Vec3 s{1, 0, 0}, t{0, 1, 0}, n{0, 0, 1};

    constexpr Frame() = default;
    constexpr Frame(const Vec3& s_, const Vec3& t_, const Vec3& n_) : s(s_), t(t_), n(n_) {}

    // A frame whose first axis is the given unit vector (e.g. a fiber tangent).
    static Frame fromX(const Vec3& x) {
        Vec3 y, z;
        coordinateSystem(x, &y, &z);
        return {x, y, z};
    }
    // A frame whose third axis is the given unit vector (e.g. a surface normal).
    static Frame fromZ(const Vec3& z) {
        Vec3 x, y;
        coordinateSystem(z, &x, &y);
        return {x, y, z};
    }

    constexpr Vec3 toLocal(const Vec3& w) const { return {dot(w, s), dot(w, t), dot(w, n)}; }
    constexpr Vec3 fromLocal(const Vec3& l) const { return s * l.x + t * l.y + n * l.z; }
};

// The yarn shading frame (docs/design.md 2) of a ply surface point with unit
// tangent t and outward unit normal n: local coordinates (w.t, w.b, w.n) with
// b = t x n. The gather (entry frame of a walk) and the renderer (shading
// frame of a ply hit) both use it, so the RDM and the BSDF share one frame.
inline Frame yarnFrame(const Vec3& t, const Vec3& n) { return Frame(t, cross(t, n), n); }

// Direction from the polar angle theta (from the frame's third axis, n) and
// the azimuth phi (from the first axis towards the second), in that frame.
inline Vec3 sphericalDirection(double theta, double phi) {
    const double s = std::sin(theta);
    return {s * std::cos(phi), s * std::sin(phi), std::cos(theta)};
}

}  // namespace weft
