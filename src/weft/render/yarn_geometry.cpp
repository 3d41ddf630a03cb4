#include "weft/render/yarn_geometry.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <string>

#include "weft/core/error.h"
#include "weft/core/math.h"
#include "weft/render/catmull_rom.h"

namespace weft::render {

namespace {

// Control points (and samples) closer than this times the curve's extent are
// one point: a zero-length span has no direction to frame.
constexpr double kCoincidentRelative = 1e-12;

std::string formatDouble(double v) {
    std::ostringstream os;
    os << v;
    return os.str();
}

// Unit tangent at a sample from the segments to its neighbours (dPrev = x -
// prev, dNext = next - x, either may be zero): the derivative of the parabola
// through the three points at chord-length spacing, h0 u1 + h1 u0, which is
// exact on a circle. Zero when it is undefined (both segments empty or a
// hairpin); the caller fills those in from neighbouring samples.
Vec3 chordTangent(const Vec3& dPrev, const Vec3& dNext) {
    const double h0 = length(dPrev), h1 = length(dNext);
    if (h0 > 0 && h1 > 0) {
        const Vec3 u0 = dPrev / h0, u1 = dNext / h1;
        const Vec3 t = h0 * u1 + h1 * u0;
        const double l = length(t);
        if (l > 1e-9 * (h0 + h1)) return t / l;
        return u1;  // a hairpin: follow the curve out of it
    }
    if (h1 > 0) return dNext / h1;
    if (h0 > 0) return dPrev / h0;
    return {};
}

// r made orthogonal to the unit vector t and normalised; any unit normal of t
// when r is (nearly) parallel to it.
Vec3 orthonormalise(const Vec3& r, const Vec3& t) {
    const Vec3 p = r - dot(r, t) * t;
    const double l = length(p);
    if (l > 1e-6) return p / l;
    Vec3 s, u;
    coordinateSystem(t, &s, &u);
    return s;
}

// One step of the double reflection method (Wang et al. 2008, Algorithm
// "DR"): reflect (t0, r0) in the bisector plane of x0 x1, then in the plane
// that takes the reflected t0 to t1. Returns the normal at x1.
Vec3 doubleReflection(const Vec3& x0, const Vec3& t0, const Vec3& r0, const Vec3& x1,
                      const Vec3& t1) {
    const Vec3 v1 = x1 - x0;
    const double c1 = dot(v1, v1);
    if (!(c1 > 0)) return orthonormalise(r0, t1);  // no step: project
    const Vec3 rL = r0 - (2.0 / c1) * dot(v1, r0) * v1;
    const Vec3 tL = t0 - (2.0 / c1) * dot(v1, t0) * v1;
    const Vec3 v2 = t1 - tL;
    const double c2 = dot(v2, v2);
    // c2 ~ 0 only where the first reflection already maps t0 to t1 (a cusp).
    const Vec3 r1 = c2 > 1e-24 ? rL - (2.0 / c2) * dot(v2, rL) * v2 : rL;
    // Reflections are exact isometries; re-orthonormalising only removes the
    // rounding drift of 10^4 steps.
    return orthonormalise(r1, t1);
}

// Fills tangents (unless given), arc lengths, the rotation-minimising frame
// and, for closed curves, the holonomy correction; points, radius and closed
// are set. `tangents` may hold analytic (unnormalised) derivatives.
void frameSamples(FramedCurve& c, bool haveTangents) {
    const size_t n = c.points.size();
    const std::vector<Vec3>& x = c.points;

    c.arcLength.resize(n);
    double s = 0;
    for (size_t i = 0; i < n; ++i) {
        c.arcLength[i] = s;
        if (i + 1 < n) s += length(x[i + 1] - x[i]);
    }
    const double closing = c.closed ? length(x[0] - x[n - 1]) : 0.0;
    c.length = s + closing;

    // Tangents: normalised analytic derivatives where they are usable, else
    // from the neighbouring samples; the few undefined ones (hairpins, zero
    // segments of an offset curve) copy the nearest defined one.
    c.tangents.resize(n);
    for (size_t i = 0; i < n; ++i) {
        if (haveTangents) {
            const double l = length(c.tangents[i]);
            if (l > 0 && std::isfinite(l)) {
                c.tangents[i] = c.tangents[i] / l;
                continue;
            }
        }
        const bool hasPrev = i > 0 || c.closed, hasNext = i + 1 < n || c.closed;
        const Vec3 dPrev = hasPrev ? x[i] - x[i == 0 ? n - 1 : i - 1] : Vec3{};
        const Vec3 dNext = hasNext ? x[i + 1 == n ? 0 : i + 1] - x[i] : Vec3{};
        c.tangents[i] = chordTangent(dPrev, dNext);
    }
    size_t firstDefined = n;
    for (size_t i = 0; i < n && firstDefined == n; ++i)
        if (c.tangents[i] != Vec3{}) firstDefined = i;
    if (firstDefined == n) {
        std::fill(c.tangents.begin(), c.tangents.end(), Vec3{0, 0, 1});
    } else {
        for (size_t i = 0; i < firstDefined; ++i) c.tangents[i] = c.tangents[firstDefined];
        for (size_t i = firstDefined + 1; i < n; ++i)
            if (c.tangents[i] == Vec3{}) c.tangents[i] = c.tangents[i - 1];
    }

    // Double reflection from coordinateSystem(T_0).
    const std::vector<Vec3>& t = c.tangents;
    c.normals.resize(n);
    c.binormals.resize(n);
    Vec3 b0;
    coordinateSystem(t[0], &c.normals[0], &b0);
    for (size_t i = 0; i + 1 < n; ++i)
        c.normals[i + 1] = doubleReflection(x[i], t[i], c.normals[i], x[i + 1], t[i + 1]);

    c.holonomy = 0;
    if (c.closed && c.length > 0) {
        // The frame carried once around the loop comes back turned by the
        // holonomy about T_0; turning sample i by -holonomy s_i / L closes it
        // with a uniform (and so the least) extra twist.
        const Vec3 r0 = c.normals[0], rb0 = cross(t[0], r0);
        const Vec3 back = doubleReflection(x[n - 1], t[n - 1], c.normals[n - 1], x[0], t[0]);
        c.holonomy = std::atan2(dot(back, rb0), dot(back, r0));
        for (size_t i = 1; i < n; ++i) {
            const double a = -c.holonomy * c.arcLength[i] / c.length;
            const Vec3 b = cross(t[i], c.normals[i]);
            c.normals[i] = std::cos(a) * c.normals[i] + std::sin(a) * b;
        }
    }
    for (size_t i = 0; i < n; ++i) c.binormals[i] = cross(t[i], c.normals[i]);
}

// Integral of rate / R(u) du at every sample by the trapezoid rule (exact for
// a constant radius); for closed curves `total` gets the loop's integral.
std::vector<double> turnIntegral(const FramedCurve& c, double rate, double* total) {
    const size_t n = c.size();
    std::vector<double> angle(n);
    double a = 0;
    for (size_t i = 0; i < n; ++i) {
        angle[i] = a;
        if (i + 1 < n) {
            const double h = c.arcLength[i + 1] - c.arcLength[i];
            a += rate * h * 0.5 * (1.0 / c.radius[i] + 1.0 / c.radius[i + 1]);
        }
    }
    if (c.closed) {
        const double h = c.length - c.arcLength[n - 1];
        a += rate * h * 0.5 * (1.0 / c.radius[n - 1] + 1.0 / c.radius[0]);
    }
    *total = a;
    return angle;
}

void checkFramed(const FramedCurve& c, const char* what) {
    const size_t n = c.size();
    if (n < 2 || c.tangents.size() != n || c.normals.size() != n || c.binormals.size() != n ||
        c.arcLength.size() != n || c.radius.size() != n ||
        !(c.colours.empty() || c.colours.size() == n)) {
        throw std::invalid_argument(std::string(what) +
                                    ": needs a framed curve of >= 2 samples (from frameCurve)");
    }
}

}  // namespace

FramedCurve frameCurve(const Curve& curve, double scale, std::optional<double> radius,
                       double maxStep, const std::string& source, size_t curveIndex) {
    const std::string name = source + ": curve " + std::to_string(curveIndex);
    if (!(maxStep > 0 && std::isfinite(maxStep)))
        throw std::invalid_argument("frameCurve: maxStep must be finite and > 0, got " +
                                    formatDouble(maxStep));
    if (!(scale > 0 && std::isfinite(scale)))
        throw InputError(name + ": scale must be finite and > 0, got " + formatDouble(scale));
    if (radius && !(*radius > 0 && std::isfinite(*radius)))
        throw InputError(name + ": radius must be finite and > 0, got " + formatDouble(*radius));
    if (!radius) {
        if (curve.radii.empty())
            throw InputError(name + ": the curve has no per-point radii and no yarn radius " +
                             "is given (set the yarn's \"radius\")");
        if (curve.radii.size() != curve.points.size())
            throw InputError(name + ": " + std::to_string(curve.radii.size()) + " radii for " +
                             std::to_string(curve.points.size()) + " points");
    }
    const bool coloured = !curve.colours.empty();
    if (coloured && curve.colours.size() != curve.points.size())
        throw InputError(name + ": " + std::to_string(curve.colours.size()) + " colours for " +
                         std::to_string(curve.points.size()) + " points");

    // Scaled control points and radii, checked, with coincident neighbours dropped.
    Bounds3 box;
    for (const Vec3& p : curve.points) {
        const Vec3 q = p * scale;
        if (!isFinite(q))
            throw InputError(name + ": point " + formatDouble(p.x) + " " + formatDouble(p.y) + " " +
                             formatDouble(p.z) + " times scale is not finite");
        box.extend(q);
    }
    const double extent = box.empty() ? 0.0 : length(box.hi - box.lo);
    const double eps = kCoincidentRelative * extent;
    std::vector<Vec3> p;
    std::vector<double> r;
    std::vector<Rgb> col;  // empty unless coloured
    p.reserve(curve.points.size());
    r.reserve(curve.points.size());
    for (size_t i = 0; i < curve.points.size(); ++i) {
        const Vec3 q = curve.points[i] * scale;
        const double ri = radius ? *radius : curve.radii[i] * scale;
        if (!(ri > 0 && std::isfinite(ri)))
            throw InputError(name + ": radius of point " + std::to_string(i) +
                             " times scale must be finite and > 0, got " + formatDouble(ri));
        if (!p.empty() && length(q - p.back()) <= eps) continue;
        p.push_back(q);
        r.push_back(ri);
        if (coloured) col.push_back(curve.colours[i]);
    }
    while (curve.closed && p.size() > 1 && length(p.back() - p.front()) <= eps) {
        p.pop_back();
        r.pop_back();
        if (coloured) col.pop_back();
    }
    if (p.size() < 2)
        throw InputError(name + ": fewer than 2 distinct points (" +
                         std::to_string(curve.points.size()) + " points" +
                         (curve.points.size() >= 2 ? ", all coincident)" : ")"));
    if (curve.closed && p.size() < 3)
        throw InputError(name + ": a closed curve needs at least 3 distinct points, got 2");

    const size_t n = p.size();
    const bool closed = curve.closed;
    const bool spline = curve.basis == CurveBasis::CatmullRom;
    const size_t spans = closed ? n : n - 1;
    // Catmull-Rom neighbours: wrap around a closed curve; reflect the end
    // points of an open one (P_-1 = 2 P_0 - P_1), see the header.
    const auto spanAt = [&](size_t i) { return catmullRomSpan(p, closed, i); };

    // Pieces per span, counted before anything large is allocated.
    std::vector<int64_t> pieces(spans);
    double total = closed ? 0.0 : 1.0;
    for (size_t i = 0; i < spans; ++i) {
        const double bound = spline ? spanAt(i).speedBound() : length(p[(i + 1) % n] - p[i]);
        const double m = std::max(1.0, std::ceil(bound / maxStep));
        total += m;
        if (!(total <= static_cast<double>(kMaxCurveSamples)))
            throw InputError(name + ": more than " + std::to_string(kMaxCurveSamples) +
                             " samples at a spacing of " + formatDouble(maxStep) +
                             " (curve too long for its radius and twist)");
        pieces[i] = static_cast<int64_t>(m);
    }

    FramedCurve c;
    c.closed = closed;
    const auto count = static_cast<size_t>(total);
    c.points.reserve(count);
    c.radius.reserve(count);
    c.tangents.reserve(count);
    if (coloured) c.colours.reserve(count);
    // Sample at parameter u of span i (u = 1: its end point), radius and
    // colour linear in u.
    const auto add = [&](size_t i, double u, const Vec3& x, const Vec3& d) {
        if (!c.points.empty() && length(x - c.points.back()) <= eps) return;
        const size_t i1 = (i + 1) % n;
        c.points.push_back(x);
        c.tangents.push_back(d);
        c.radius.push_back(u == 1.0 ? r[i1] : (1.0 - u) * r[i] + u * r[i1]);
        if (coloured) {
            // In steps of 1/kColourSteps of the span (header): the colours
            // are materials, and a span then makes at most kColourSteps - 1 new ones.
            const double uq = std::round(u * kColourSteps) / kColourSteps;
            const bool atStart = uq == 0.0 || col[i] == col[i1];
            c.colours.push_back(atStart     ? col[i]
                                : uq == 1.0 ? col[i1]
                                            : (1.0 - uq) * col[i] + uq * col[i1]);
        }
    };
    for (size_t i = 0; i < spans; ++i) {
        const size_t i1 = (i + 1) % n;
        const int64_t m = pieces[i];
        if (spline) {
            const CatmullRomSpan span = spanAt(i);
            for (int64_t j = 0; j < m; ++j) {
                const double u = static_cast<double>(j) / static_cast<double>(m);
                add(i, u, span.position(u), span.derivative(u));
            }
            if (!closed && i + 1 == spans) add(i, 1.0, p[i1], span.derivative(1.0));
        } else {
            const Vec3 d = p[i1] - p[i];
            for (int64_t j = 0; j < m; ++j) {
                const double u = static_cast<double>(j) / static_cast<double>(m);
                add(i, u, p[i] + u * d, Vec3{});
            }
            if (!closed && i + 1 == spans) add(i, 1.0, p[i1], Vec3{});
        }
    }
    while (closed && c.points.size() > 1 && length(c.points.back() - c.points.front()) <= eps) {
        c.points.pop_back();
        c.tangents.pop_back();
        c.radius.pop_back();
        if (coloured) c.colours.pop_back();
    }
    if (c.points.size() < (closed ? 3u : 2u))
        throw InputError(name + ": the sampled curve degenerates to fewer than " +
                         (closed ? "3" : "2") + " distinct points");

    frameSamples(c, spline);
    return c;
}

double plyRadius(double yarnRadius, int plies) {
    if (plies < 1) throw InputError("plies must be >= 1, got " + std::to_string(plies));
    if (!(yarnRadius > 0 && std::isfinite(yarnRadius)))
        throw InputError("yarn radius must be finite and > 0, got " + formatDouble(yarnRadius));
    if (plies == 1) return yarnRadius;
    // k circles of radius R_ply around a centre at distance R - R_ply touch
    // their neighbours when (R - R_ply) sin(pi / k) = R_ply.
    const double s = std::sin(kPi / plies);
    return yarnRadius * s / (1.0 + s);
}

std::vector<FramedCurve> plyCurves(const FramedCurve& yarn, int plies, double plyTwist) {
    checkFramed(yarn, "plyCurves");
    if (!std::isfinite(plyTwist))
        throw InputError("ply_twist must be finite, got " + formatDouble(plyTwist));
    const double plyFraction = plyRadius(1.0, plies);  // validates plies
    for (double rad : yarn.radius)
        if (!(rad > 0 && std::isfinite(rad)))
            throw std::invalid_argument("plyCurves: yarn radius " + formatDouble(rad) +
                                        " is not finite and > 0");
    if (plies == 1) return {yarn};  // one ply fills the yarn: R_ply = R, no offset

    // theta(s) - theta(0) = integral pi ply_twist / R(u) du (the helix turns by
    // pi ply_twist per yarn radius of length, like the fibers of docs/design.md 4).
    double loopTurn = 0;
    std::vector<double> phase = turnIntegral(yarn, kPi * plyTwist, &loopTurn);
    const size_t n = yarn.size();
    const int k = plies;
    size_t curves = static_cast<size_t>(k), laps = 1;
    if (yarn.closed) {
        // Round the loop's turn to 2 pi m / k so the plies close seamlessly.
        const double quantum = kTwoPi / k;
        const double ratio = loopTurn / quantum;
        if (!(std::abs(ratio) < 1e15))
            throw InputError("ply_twist " + formatDouble(plyTwist) +
                             " turns the plies too often around a closed yarn of length " +
                             formatDouble(yarn.length));
        auto m = static_cast<int64_t>(std::llround(ratio));
        if (m == 0 && plyTwist != 0) m = plyTwist > 0 ? 1 : -1;
        if (loopTurn != 0) {
            const double factor = static_cast<double>(m) * quantum / loopTurn;
            for (double& a : phase) a *= factor;
        }
        loopTurn = static_cast<double>(m) * quantum;
        curves = static_cast<size_t>(std::gcd(std::abs(m), static_cast<int64_t>(k)));
        laps = static_cast<size_t>(k) / curves;
    }

    std::vector<FramedCurve> result(curves);
    for (size_t c = 0; c < curves; ++c) {
        FramedCurve& ply = result[c];
        ply.closed = yarn.closed;
        ply.points.reserve(laps * n);
        ply.radius.reserve(laps * n);
        ply.colours.reserve(yarn.colours.empty() ? 0 : laps * n);
        for (size_t lap = 0; lap < laps; ++lap) {
            // After `lap` loops ply c has become ply c + lap m (mod k): its
            // phase runs on continuously.
            const double start =
                kTwoPi * static_cast<double>(c) / k + static_cast<double>(lap) * loopTurn;
            for (size_t i = 0; i < n; ++i) {
                const double theta = start + phase[i];
                const double rPly = plyFraction * yarn.radius[i];
                const double offset = yarn.radius[i] - rPly;
                ply.points.push_back(yarn.points[i] +
                                     offset * (std::cos(theta) * yarn.normals[i] +
                                               std::sin(theta) * yarn.binormals[i]));
                ply.radius.push_back(rPly);
                if (!yarn.colours.empty()) ply.colours.push_back(yarn.colours[i]);
            }
        }
        frameSamples(ply, false);
    }
    return result;
}

Tube toTube(const FramedCurve& curve) {
    Tube tube;
    tube.points = curve.points;
    tube.radii.reserve(curve.radius.size());
    for (double r : curve.radius) tube.radii.push_back(static_cast<float>(r));
    tube.closed = curve.closed;
    return tube;
}

std::vector<Tube> fiberTubes(const FramedCurve& ply, const PlyParams& params, uint64_t seed) {
    checkFramed(ply, "fiberTubes");
    const double r0 = ply.radius[0];
    for (double rad : ply.radius)
        if (!(rad > 0 && std::isfinite(rad)))
            throw std::invalid_argument("fiberTubes: ply radius " + formatDouble(rad) +
                                        " is not finite and > 0");
    // The cross-section of the gather's generator (ply/ply.h) at radius
    // R_ply(0); the length does not affect the placement.
    const PlyGeometry layout = generatePly(params, r0, r0, seed);

    // Cross-section turn psi(s) = integral pi alpha / R_ply(u) du (docs/design.md 4:
    // right-handed about T, N and B standing for x and y).
    double loopTurn = 0;
    std::vector<double> psi = turnIntegral(ply, kPi * params.twist, &loopTurn);
    if (ply.closed && params.twist > 0) {
        // A whole number m >= 1 of turns per loop: each fiber closes on itself.
        const double m = std::max(1.0, std::round(loopTurn / kTwoPi));
        const double factor = m * kTwoPi / loopTurn;
        for (double& a : psi) a *= factor;
    }

    const size_t n = ply.size();
    std::vector<double> cosPsi(n), sinPsi(n), scale(n);
    for (size_t i = 0; i < n; ++i) {
        cosPsi[i] = std::cos(psi[i]);
        sinPsi[i] = std::sin(psi[i]);
        scale[i] = ply.radius[i] / r0;
    }

    std::vector<Tube> tubes(layout.centres.size());
    for (size_t f = 0; f < tubes.size(); ++f) {
        const double cx = layout.centres[f][0], cy = layout.centres[f][1];
        Tube& tube = tubes[f];
        tube.closed = ply.closed;
        tube.points.resize(n);
        tube.radii.resize(n);
        for (size_t i = 0; i < n; ++i) {
            // Counter-clockwise by psi seen from the tip of T (PlyGeometry::fiberCentre).
            const double x = scale[i] * (cosPsi[i] * cx - sinPsi[i] * cy);
            const double y = scale[i] * (sinPsi[i] * cx + cosPsi[i] * cy);
            tube.points[i] = ply.points[i] + x * ply.normals[i] + y * ply.binormals[i];
            tube.radii[i] = static_cast<float>(layout.fiberRadius * scale[i]);
        }
    }
    return tubes;
}

double sampleStep(double yarnRadius, int plies, double plyTwist, const PlyParams* fibers,
                  int pointsPerTwist) {
    if (pointsPerTwist < 1)
        throw std::invalid_argument("sampleStep: pointsPerTwist must be >= 1, got " +
                                    std::to_string(pointsPerTwist));
    const double rPly = plyRadius(yarnRadius, plies);  // validates R and plies
    if (!std::isfinite(plyTwist))
        throw InputError("ply_twist must be finite, got " + formatDouble(plyTwist));
    const double n = pointsPerTwist;
    const double r = yarnRadius;
    double step = r / 4.0;
    if (plyTwist != 0) step = std::min(step, 2.0 * r / std::abs(plyTwist) / n);
    if (fibers) {
        fibers->validate();
        if (fibers->twist > 0) {
            // The fibers twist per unit of ply length; a ply on a straight yarn
            // is longer than the yarn by the stretch of its helix.
            const double stretch = std::sqrt(1.0 + sqr(kPi * plyTwist * (r - rPly) / r));
            step = std::min(step, 2.0 * rPly / fibers->twist / (n * stretch));
        }
    }
    return step;
}

}  // namespace weft::render
