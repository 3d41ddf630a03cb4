// weft/render/catmull_rom.h — the uniform Catmull-Rom spans of a curve
// (yarn_geometry.h step 1): one definition for the renderer's sampling and for
// `weft scene export --mitsuba`, which writes such curves as polylines.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

#include "weft/core/vec.h"

namespace weft::render {

// One uniform Catmull-Rom span from p1 to p2 (tension 0.5) in power form:
//   p(t) = c0 + c1 t + c2 t^2 + c3 t^3
//        = 0.5 (2 p1 + (p2 - p0) t + (2 p0 - 5 p1 + 4 p2 - p3) t^2
//               + (-p0 + 3 p1 - 3 p2 + p3) t^3).
struct CatmullRomSpan {
    Vec3 c0, c1, c2, c3;

    CatmullRomSpan(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3)
        : c0(p1),
          c1(0.5 * (p2 - p0)),
          c2(p0 - 2.5 * p1 + 2.0 * p2 - 0.5 * p3),
          c3(0.5 * (3.0 * (p1 - p2) + p3 - p0)) {}

    Vec3 position(double t) const { return c0 + t * (c1 + t * (c2 + t * c3)); }
    Vec3 derivative(double t) const { return c1 + t * (2.0 * c2 + t * (3.0 * c3)); }

    // p'(t) is a quadratic Bezier curve with control points p'(0), p'(0) + c2
    // and p'(1); it lies in their convex hull, so the largest of their lengths
    // bounds the speed, and (1/m) times it the arc length of every 1/m piece.
    double speedBound() const {
        return std::max({length(c1), length(c1 + c2), length(derivative(1.0))});
    }
};

// Span i (from point i to i + 1) of the curve through `p` (at least 2
// points): its neighbours wrap around a closed curve; an open one's missing
// end neighbours are the reflected points P_-1 = 2 P_0 - P_1 and
// P_n = 2 P_n-1 - P_n-2.
inline CatmullRomSpan catmullRomSpan(const std::vector<Vec3>& p, bool closed, size_t i) {
    const auto n = static_cast<ptrdiff_t>(p.size());
    const auto at = [&](ptrdiff_t j) -> Vec3 {
        if (closed) return p[static_cast<size_t>(((j % n) + n) % n)];
        if (j < 0) return 2.0 * p[0] - p[1];
        if (j >= n) return 2.0 * p[static_cast<size_t>(n - 1)] - p[static_cast<size_t>(n - 2)];
        return p[static_cast<size_t>(j)];
    };
    const auto j = static_cast<ptrdiff_t>(i);
    return CatmullRomSpan(at(j - 1), at(j), at(j + 1), at(j + 2));
}

}  // namespace weft::render
