#include "weft/gather/ply_tracer.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "weft/core/error.h"
#include "weft/core/json_message.h"
#include "weft/core/limits.h"
#include "weft/core/math.h"

namespace weft {

namespace {

// RTCIntersectContext extended with the fiber to skip (Embree's documented
// way to pass data to filter functions: the context is the first member).
struct ExcludeContext {
    RTCIntersectContext context;
    int excludedFiber;
};

void skipExcludedFiber(const RTCFilterFunctionNArguments* args) {
    const auto* ctx = reinterpret_cast<const ExcludeContext*>(args->context);
    const int fiber = static_cast<int>(reinterpret_cast<intptr_t>(args->geometryUserPtr));
    if (fiber == ctx->excludedFiber) args->valid[0] = 0;
}

ExcludeContext makeContext(int excludedFiber) {
    ExcludeContext ctx;
    rtcInitIntersectContext(&ctx.context);
    ctx.context.filter = excludedFiber >= 0 ? &skipExcludedFiber : nullptr;
    ctx.excludedFiber = excludedFiber;
    return ctx;
}

// One Embree query over [0, tfar]; returns the hit distance and sets *fiber,
// or returns a negative value when nothing is hit.
double intersect(RTCScene scene, ExcludeContext& ctx, const Vec3& org, const Vec3& dir, double tfar,
                 int* fiber) {
    RTCRayHit rh;
    initRay(rh, org, dir, tfar);
    rtcIntersect1(scene, &ctx.context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return -1.0;
    *fiber = static_cast<int>(rh.hit.geomID);
    return rh.ray.tfar;
}

}  // namespace

void PeriodicPlyTracer::validateSegmentsPerTwist(int segmentsPerTwist) {
    checkRange("segments per twist =", segmentsPerTwist, 16, 65536);
}

PeriodicPlyTracer::Layout PeriodicPlyTracer::layout(const PlyParams& params, double radius,
                                                    double fiberRadius, int segmentsPerTwist,
                                                    size_t fibers, FiberPrimitive primitive) {
    validateSegmentsPerTwist(segmentsPerTwist);
    const double r = fiberRadius;
    const bool straight = params.twist == 0;
    Layout l;
    l.period = straight ? 4.0 * radius : 2.0 * radius / params.twist;  // PlyGeometry::twistPeriod
    // A twist below 2R / DBL_MAX (a denormal) has no finite period.
    if (!std::isfinite(l.period))
        throw InputError("ply: twist (alpha) = " + formatNumber(params.twist) +
                         " has no finite twist period 2R / alpha (use 0 for a straight ply)");
    // A fiber tilted by at most atan(pi alpha) reaches r / cos(tilt) < r (1 + pi alpha)
    // along z from its centre line; add one segment for the chords.
    l.perPeriod = straight ? 1 : segmentsPerTwist;
    l.step = l.period / l.perPeriod;
    l.margin = r * (1.0 + kPi * params.twist) + (straight ? 0.0 : l.step) + 1e-3 * radius;
    const bool cubic = primitive == FiberPrimitive::RoundCatmullRom;
    // A Catmull-Rom segment needs one more control point on each side. In
    // double until the memory budget has bounded it: a large twist makes the
    // margin many periods long (twist 1e6: 4e12 points per fiber).
    const double extra = straight ? 0.0 : std::ceil(l.margin / l.step) + (cubic ? 1 : 0);
    const double points = straight ? (cubic ? 4 : 2) : l.perPeriod + 2 * extra + 1;
    // Per control point: the float4 vertex, the double copy in lines_, an
    // index and a flag, and Embree's BVH (about 100 bytes per segment).
    checkMemoryBudget(static_cast<double>(fibers) * points * 150.0,
                      "the explicit ply (" + std::to_string(fibers) + " fibers x " +
                          formatNumber(points) + " points)");
    if (!(points <= std::numeric_limits<int>::max()))
        throw InputError("ply: twist (alpha) = " + formatNumber(params.twist) + " needs " +
                         formatNumber(points) + " points per fiber (at most 2^31 - 1)");
    l.extra = static_cast<int>(extra);
    l.points = static_cast<int>(points);
    return l;
}

PeriodicPlyTracer::PeriodicPlyTracer(const PlyGeometry& ply, int segmentsPerTwist,
                                     FiberPrimitive primitive)
    : ply_(ply) {
    const double radius = ply_.radius, r = ply_.fiberRadius;
    const bool straight = ply_.params.twist == 0;
    const Layout l = layout(ply_.params, radius, ply_.fiberRadius, segmentsPerTwist,
                            ply_.centres.size(), primitive);
    period_ = l.period;
    margin_ = l.margin;
    const bool cubic = primitive == FiberPrimitive::RoundCatmullRom;
    const double step = l.step;
    const int extra = l.extra;
    const double z0 = straight ? -margin_ : -extra * step;
    const int points = l.points;
    const int segments = cubic ? points - 3 : points - 1;
    const double dz = straight ? (period_ + 2.0 * margin_) / (points - 1 - (cubic ? 2 : 0)) : step;
    const double zStart = straight && cubic ? z0 - dz : z0;
    scene_ = rtcNewScene(device_.get());
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
    lines_.resize(ply_.centres.size());
    for (int i = 0; i < static_cast<int>(ply_.centres.size()); ++i) {
        RTCGeometry geom =
            rtcNewGeometry(device_.get(), cubic ? RTC_GEOMETRY_TYPE_ROUND_CATMULL_ROM_CURVE
                                                : RTC_GEOMETRY_TYPE_ROUND_LINEAR_CURVE);
        auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
            geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), points));
        auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
            geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, sizeof(unsigned), segments));
        auto* flags = cubic ? nullptr
                            : static_cast<unsigned char*>(rtcSetNewGeometryBuffer(
                                  geom, RTC_BUFFER_TYPE_FLAGS, 0, RTC_FORMAT_UCHAR, 1, segments));
        device_.check("allocating fiber geometry");
        lines_[i].resize(points);
        for (int k = 0; k < points; ++k) {
            const Vec3 p = ply_.fiberCentre(i, zStart + k * dz);
            lines_[i][k] = p;
            vertices[4 * k + 0] = static_cast<float>(p.x);
            vertices[4 * k + 1] = static_cast<float>(p.y);
            vertices[4 * k + 2] = static_cast<float>(p.z);
            vertices[4 * k + 3] = static_cast<float>(r);
        }
        for (int k = 0; k < segments; ++k) {
            indices[k] = static_cast<unsigned>(k);
            // Joined linear segments: no double hits inside the sphere joints.
            if (flags)
                flags[k] = static_cast<unsigned char>(
                    (k > 0 ? RTC_CURVE_FLAG_NEIGHBOR_LEFT : 0) |
                    (k + 1 < segments ? RTC_CURVE_FLAG_NEIGHBOR_RIGHT : 0));
        }
        rtcSetGeometryUserData(geom, reinterpret_cast<void*>(static_cast<intptr_t>(i)));
        rtcCommitGeometry(geom);
        const unsigned id = rtcAttachGeometry(scene_, geom);
        rtcReleaseGeometry(geom);
        if (id != static_cast<unsigned>(i))
            throw std::runtime_error("unexpected Embree geometry id");
        segments_ += segments;
    }
    rtcCommitScene(scene_);
    device_.check("building the ply BVH");
}

PeriodicPlyTracer::~PeriodicPlyTracer() {
    if (scene_) rtcReleaseScene(scene_);
}

double PeriodicPlyTracer::cylinderExitDistance(const Vec3& org, const Vec3& dir) const {
    // |o + t d|^2 = R^2 in the x-y plane: a t^2 + 2 b t + c = 0, larger root.
    const double a = dir.x * dir.x + dir.y * dir.y;
    if (a <= 0) return std::numeric_limits<double>::infinity();
    const double b = org.x * dir.x + org.y * dir.y;
    const double c = org.x * org.x + org.y * org.y - ply_.radius * ply_.radius;
    const double disc = std::max(0.0, b * b - a * c);
    // Stable form of (-b + sqrt(disc)) / a.
    const double q = std::sqrt(disc);
    const double t = b <= 0 ? (-b + q) / a : -c / (b + q);
    return std::max(0.0, t);
}

double PeriodicPlyTracer::intersectOnce(const Vec3& org, const Vec3& dir, double tfar,
                                        int excludedFiber) const {
    ExcludeContext ctx = makeContext(excludedFiber);
    int fiber = -1;
    return intersect(scene_, ctx, org, dir, tfar, &fiber);
}

PlyTraceHit PeriodicPlyTracer::trace(const Vec3& orgIn, const Vec3& dir, int excludedFiber,
                                     int maxWraps) const {
    PlyTraceHit result;
    Vec3 org = orgIn;
    double toSide = cylinderExitDistance(org, dir);
    ExcludeContext ctx = makeContext(excludedFiber);
    for (int wrap = 0; wrap <= maxWraps; ++wrap) {
        double toFace = std::numeric_limits<double>::infinity();
        if (dir.z > 0) toFace = (period_ - org.z) / dir.z;
        if (dir.z < 0) toFace = -org.z / dir.z;
        toFace = std::max(0.0, toFace);
        const double tMax = std::min(toSide, toFace);

        int fiber = -1;
        const double t = intersect(scene_, ctx, org, dir, tMax, &fiber);
        ++result.raysTraced;
        if (t >= 0) {
            result.kind = PlyTraceHit::Kind::Fiber;
            result.fiber = fiber;
            result.point = org + dir * t;
            // Keep the point inside the slab despite float rounding.
            result.point.z = std::clamp(result.point.z, 0.0, std::nextafter(period_, 0.0));
            return result;
        }
        if (toSide <= toFace) {
            result.kind = PlyTraceHit::Kind::ExitSide;
            result.point = org + dir * toSide;
            result.point.z = std::clamp(result.point.z, 0.0, period_);
            return result;
        }
        // Continue from the opposite slab face: the ply is periodic in z.
        org = org + dir * toFace;
        org.z = dir.z > 0 ? 0.0 : period_;
        result.periodShift += dir.z > 0 ? 1 : -1;
        toSide -= toFace;
    }
    result.kind = PlyTraceHit::Kind::ExitAxial;
    return result;
}

}  // namespace weft
