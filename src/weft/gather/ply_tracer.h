// weft/gather/ply_tracer.h — ray tracing through an explicit, infinitely long ply.
//
// The ply of docs/design.md 4 (axis +z, radius R, fibers as right-handed helices)
// is invariant under a shift of one twist period P = 2R / alpha along z
// (the cross-section turns by exactly 2 pi), so one period of geometry,
// wrapped periodically in z, is an exact model of an infinitely long ply: no
// path can leave through the ends. For alpha = 0 any length is a period; we
// use 4R. Rays are traced inside the slab 0 <= z < P; a ray that reaches a
// slab face continues from the opposite face with the same x, y and
// direction. Fibers extend a margin beyond both faces so that every fiber
// surface inside the slab is present.
//
// Geometry: Embree 3 round linear curves (cones joined by spheres), one
// geometry per fiber so that the geometry id is the fiber index, with
// `segmentsPerTwist` segments per period (default 128: the chord of the helix
// deviates from it by R (1 - cos(pi / 128)) = 3e-4 R, 1% of a fleece fiber's
// radius); straight fibers (alpha = 0) are exact cylinders of one segment.
// See docs/gather.md for the choice of primitive.
//
// Far-field fiber model (docs/design.md 5): a ray leaving fiber i never hits
// fiber i again on that straight segment: an intersection filter rejects it.
#pragma once

#include <embree3/rtcore.h>

#include <cstdint>
#include <memory>

#include "weft/core/embree.h"
#include "weft/core/vec.h"
#include "weft/ply/ply.h"

namespace weft {

// How fiber centre lines are handed to Embree. Round linear curves are the
// default (measured fastest, bench/gather); round Catmull-Rom curves
// interpolate the same helix points with cubic segments.
enum class FiberPrimitive { RoundLinear, RoundCatmullRom };

struct PlyTraceHit {
    enum class Kind { Fiber, ExitSide, ExitAxial };
    Kind kind = Kind::ExitSide;
    int fiber = -1;  // for Kind::Fiber
    // Kind::Fiber: the hit point; Kind::ExitSide: where the ray leaves the
    // cylinder. Slab coordinates (0 <= z <= period): the unwrapped point is
    // point + (0, 0, periodShift * period).
    Vec3 point;
    int periodShift = 0;  // slab faces crossed upwards minus downwards
    int raysTraced = 0;
};

class PeriodicPlyTracer {
public:
    // ply.length is ignored; the slab is one twist period long.
    PeriodicPlyTracer(const PlyGeometry& ply, int segmentsPerTwist = 128,
                      FiberPrimitive primitive = FiberPrimitive::RoundLinear);
    ~PeriodicPlyTracer();
    PeriodicPlyTracer(const PeriodicPlyTracer&) = delete;
    PeriodicPlyTracer& operator=(const PeriodicPlyTracer&) = delete;

    const PlyGeometry& ply() const { return ply_; }
    double period() const { return period_; }
    double margin() const { return margin_; }
    int64_t segmentCount() const { return segments_; }
    // Bytes Embree holds for geometry and BVH.
    int64_t embreeBytes() const { return device_.allocatedBytes(); }
    // The fiber centre lines as traced (z from -margin to period + margin).
    const std::vector<std::vector<Vec3>>& centreLines() const { return lines_; }

    // Follows the ray from org (inside the bounding cylinder, 0 <= z < period)
    // along the unit direction dir until it hits a fiber other than
    // `excludedFiber` (-1: none) or leaves the cylinder's side. A ray that
    // wraps more than `maxWraps` times without either (almost parallel to the
    // axis) is reported as ExitAxial.
    // InputError unless segmentsPerTwist is in [16, 65536].
    static void validateSegmentsPerTwist(int segmentsPerTwist);

    // The slab and control points of a ply of `fibers` fibers of radius
    // fiberRadius, without placing them: the constructor's numbers, so that
    // a gather can refuse a ply before placing a million fibers. InputError
    // when the twist has no finite period, or the points exceed the memory
    // budget or an int.
    struct Layout {
        double period = 0, margin = 0, step = 0;
        int perPeriod = 0;  // segments per period
        int extra = 0;      // points beyond each slab face (not for straight plies)
        int points = 0;     // control points per fiber
    };
    static Layout layout(const PlyParams& params, double radius, double fiberRadius,
                         int segmentsPerTwist, size_t fibers,
                         FiberPrimitive primitive = FiberPrimitive::RoundLinear);

    PlyTraceHit trace(const Vec3& org, const Vec3& dir, int excludedFiber,
                      int maxWraps = 4096) const;

    // One plain Embree query (no wrapping): the nearest fiber hit distance in
    // [0, tfar], or a negative value. For throughput measurements.
    double intersectOnce(const Vec3& org, const Vec3& dir, double tfar, int excludedFiber) const;

    // Distance from org (inside) along dir to the cylinder side; +inf if dir is along z.
    double cylinderExitDistance(const Vec3& org, const Vec3& dir) const;

private:
    PlyGeometry ply_;
    double period_ = 0, margin_ = 0;
    int64_t segments_ = 0;
    std::vector<std::vector<Vec3>> lines_;
    EmbreeDevice device_;
    RTCScene scene_ = nullptr;
};

}  // namespace weft
