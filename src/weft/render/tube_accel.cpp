#include "weft/render/tube_accel.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace weft::render {

namespace {

// RTCIntersectContext extended with the tube the ray leaves (Embree's
// documented way to pass data to filter functions: the context comes first):
// its geometry and its segments [firstSegment, endSegment), so that the filter,
// called for every candidate hit, needs no search.
struct OriginContext {
    RTCIntersectContext context;
    unsigned geometry;
    unsigned firstSegment, endSegment;
    float selfHitDistance;
    bool surface;  // the origin is a triangle: firstSegment is its index
};

void dropOriginTubeHits(const RTCFilterFunctionNArguments* args) {
    const auto* ctx = reinterpret_cast<const OriginContext*>(args->context);
    if (RTCHitN_geomID(args->hit, args->N, 0) != ctx->geometry) return;
    const unsigned segment = RTCHitN_primID(args->hit, args->N, 0);
    if (ctx->surface) {
        if (segment == ctx->firstSegment ||
            RTCRayN_tfar(args->ray, args->N, 0) < ctx->selfHitDistance)
            args->valid[0] = 0;
        return;
    }
    if (segment < ctx->firstSegment || segment >= ctx->endSegment) return;
    const float t = RTCRayN_tfar(args->ray, args->N, 0);
    const float leaving =
        RTCRayN_dir_x(args->ray, args->N, 0) * RTCHitN_Ng_x(args->hit, args->N, 0) +
        RTCRayN_dir_y(args->ray, args->N, 0) * RTCHitN_Ng_y(args->hit, args->N, 0) +
        RTCRayN_dir_z(args->ray, args->N, 0) * RTCHitN_Ng_z(args->hit, args->N, 0);
    if (t < ctx->selfHitDistance || leaving > 0.0f) args->valid[0] = 0;
}

OriginContext makeContext(const TubeId& origin,
                          const std::vector<TubeAccel::GeometryInfo>& geometries) {
    OriginContext ctx;
    rtcInitIntersectContext(&ctx.context);
    ctx.geometry = RTC_INVALID_GEOMETRY_ID;
    ctx.firstSegment = ctx.endSegment = 0;
    ctx.selfHitDistance = 0.0f;
    ctx.surface = false;
    if (origin.valid() && geometries[origin.geometry].surface) {
        ctx.context.filter = &dropOriginTubeHits;
        ctx.geometry = origin.geometry;
        ctx.surface = true;
        ctx.firstSegment = origin.tube;
        ctx.endSegment = origin.tube + 1;
        ctx.selfHitDistance = geometries[origin.geometry].surfaceSelfHit;
    } else if (origin.valid()) {
        const TubeAccel::GeometryInfo& info = geometries[origin.geometry];
        ctx.context.filter = &dropOriginTubeHits;
        ctx.geometry = origin.geometry;
        ctx.firstSegment = info.tubeFirstSegment[origin.tube];
        ctx.endSegment = origin.tube + 1 < info.tubeFirstSegment.size()
                             ? info.tubeFirstSegment[origin.tube + 1]
                             : info.segmentCount;
        ctx.selfHitDistance =
            static_cast<float>(TubeAccel::kSelfHitDistance * info.tubeRadius[origin.tube]);
    } else {
        ctx.context.filter = nullptr;
    }
    return ctx;
}

}  // namespace

Vec3 TubeAccel::smoothTangent(const GeometryInfo& info, uint32_t segment, float u) {
    // The index buffer gives the segment's first vertex; its neighbours, where
    // the flags say it has them, are one vertex before and after.
    const float* v0 = info.vertices + 4 * static_cast<size_t>(info.indices[segment]);
    const auto point = [&](int k) { return Vec3{v0[4 * k], v0[4 * k + 1], v0[4 * k + 2]}; };
    const unsigned char flags = info.flags[segment];
    const bool left = flags & RTC_CURVE_FLAG_NEIGHBOR_LEFT;
    const bool right = flags & RTC_CURVE_FLAG_NEIGHBOR_RIGHT;
    const double w = std::clamp(static_cast<double>(u), 0.0, 1.0);
    // At a joint (exitPoint walks from joint to joint) only that vertex's
    // tangent: the blend below with the other one's weight 0.
    if ((w == 0 && left) || (w == 1 && right)) {
        const Vec3 t = w == 0 ? normalizeAnyLength(point(1) - point(-1))
                              : normalizeAnyLength(point(2) - point(0));
        return dot(t, t) > 1e-12 ? normalize(t) : normalizeAnyLength(point(1) - point(0));
    }
    const Vec3 along = normalizeAnyLength(point(1) - point(0));
    Vec3 t0 = left ? normalizeAnyLength(point(1) - point(-1)) : along;
    Vec3 t1 = right ? normalizeAnyLength(point(2) - point(0)) : along;
    // At an open end, the end tangent of the parabola through the last three
    // points (2 x the chord's direction - the inner tangent): exact on a
    // circle, the segment itself on a straight tube.
    const auto endTangent = [&](const Vec3& inner) {
        const Vec3 t = along * 2.0 - inner;
        return dot(t, t) > 1e-12 ? normalize(t) : along;
    };
    if (!left && right) t0 = endTangent(t1);
    if (left && !right) t1 = endTangent(t0);
    const Vec3 t = t0 * (1 - w) + t1 * w;
    // A hairpin (the neighbours on opposite sides) has no smooth tangent there.
    return dot(t, t) > 1e-12 ? normalize(t) : along;
}

uint32_t TubeAccel::GeometryInfo::tubeOf(uint32_t segment) const {
    const auto it = std::upper_bound(tubeFirstSegment.begin(), tubeFirstSegment.end(), segment);
    return static_cast<uint32_t>(it - tubeFirstSegment.begin()) - 1;
}

TubeAccel::TubeAccel() {
    scene_ = rtcNewScene(device_.get());
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
    device_.check("creating the scene");
}

TubeAccel::~TubeAccel() {
    if (scene_) rtcReleaseScene(scene_);
}

uint32_t TubeAccel::addGeometry(const std::vector<Tube>& tubes, int material,
                                std::vector<int> materialAlongTubes) {
    if (committed_) throw std::logic_error("TubeAccel::addGeometry after commit");
    GeometryInfo info;
    info.material = material;
    for (const Tube& tube : tubes)
        if (!materialAlongTubes.empty() && tube.segmentCount() != materialAlongTubes.size())
            throw std::logic_error(
                "TubeAccel: materialAlongTubes needs one material per segment "
                "of every tube");
    info.materialAlong = std::move(materialAlongTubes);
    // Vertex layout per tube: an open tube's points as they are; a closed
    // tube's points framed by its last point before and its first two after,
    // so that every segment, the closing one included, has both neighbours
    // one vertex away (RTC_CURVE_FLAG_NEIGHBOR_*: Embree then cuts the joint
    // spheres away inside the tube, which transmitted rays cross).
    size_t vertexCount = 0, segmentCount = 0;
    for (const Tube& tube : tubes) {
        if (tube.points.size() < 2 || tube.radii.size() != tube.points.size())
            throw std::logic_error("TubeAccel: a tube needs >= 2 points and one radius per point");
        vertexCount += tube.points.size() + (tube.closed ? 3 : 0);
        segmentCount += tube.segmentCount();
    }
    if (segmentCount == 0) return kNoTube;
    if (vertexCount > std::numeric_limits<uint32_t>::max() / 2)
        throw std::runtime_error("TubeAccel: too many curve vertices in one geometry");

    RTCGeometry geom = rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_ROUND_LINEAR_CURVE);
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), vertexCount));
    auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, sizeof(unsigned), segmentCount));
    auto* flags = static_cast<unsigned char*>(
        rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_FLAGS, 0, RTC_FORMAT_UCHAR, 1, segmentCount));
    device_.check("allocating curve geometry");

    size_t v = 0, s = 0;
    auto putVertex = [&](const Tube& tube, size_t i) {
        const Vec3& p = tube.points[i];
        vertices[4 * v + 0] = static_cast<float>(p.x);
        vertices[4 * v + 1] = static_cast<float>(p.y);
        vertices[4 * v + 2] = static_cast<float>(p.z);
        vertices[4 * v + 3] = tube.radii[i];
        ++v;
    };
    for (const Tube& tube : tubes) {
        const size_t n = tube.points.size();
        info.tubeFirstSegment.push_back(static_cast<uint32_t>(s));
        info.tubeRadius.push_back(*std::max_element(tube.radii.begin(), tube.radii.end()));
        const size_t segments = tube.segmentCount();
        if (tube.closed) putVertex(tube, n - 1);
        const size_t first = v;
        for (size_t i = 0; i < n; ++i) putVertex(tube, i);
        if (tube.closed) putVertex(tube, 0), putVertex(tube, 1);
        for (size_t k = 0; k < segments; ++k, ++s) {
            indices[s] = static_cast<unsigned>(first + k);
            const bool left = tube.closed || k > 0;
            const bool right = tube.closed || k + 1 < segments;
            flags[s] = static_cast<unsigned char>((left ? RTC_CURVE_FLAG_NEIGHBOR_LEFT : 0) |
                                                  (right ? RTC_CURVE_FLAG_NEIGHBOR_RIGHT : 0));
        }
    }
    info.segmentCount = static_cast<uint32_t>(segmentCount);
    info.vertices = vertices;
    info.indices = indices;
    info.flags = flags;
    rtcCommitGeometry(geom);
    const unsigned id = rtcAttachGeometry(scene_, geom);
    rtcReleaseGeometry(geom);
    device_.check("adding curve geometry");
    if (id != geometries_.size()) throw std::runtime_error("unexpected Embree geometry id");
    tubes_ += static_cast<int64_t>(tubes.size());
    segments_ += static_cast<int64_t>(segmentCount);
    geometries_.push_back(std::move(info));
    return id;
}

uint32_t TubeAccel::addTriangles(const std::vector<Vec3>& vertices,
                                 const std::vector<std::array<uint32_t, 3>>& triangles,
                                 int material) {
    if (committed_) throw std::logic_error("TubeAccel::addTriangles after commit");
    if (triangles.empty()) return kNoTube;
    GeometryInfo info;
    info.material = material;
    info.surface = true;
    RTCGeometry geom = rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertices.size()));
    auto* index = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), triangles.size()));
    device_.check("allocating triangle geometry");
    Vec3 lo = vertices.front(), hi = vertices.front();
    for (size_t i = 0; i < vertices.size(); ++i) {
        const Vec3& p = vertices[i];
        v[3 * i] = static_cast<float>(p.x), v[3 * i + 1] = static_cast<float>(p.y),
              v[3 * i + 2] = static_cast<float>(p.z);
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
    for (size_t t = 0; t < triangles.size(); ++t)
        for (int k = 0; k < 3; ++k) {
            if (triangles[t][k] >= vertices.size())
                throw std::logic_error("TubeAccel: a triangle index beyond the vertices");
            index[3 * t + k] = triangles[t][k];
        }
    info.surfaceSelfHit = static_cast<float>(kSurfaceSelfHit * length(hi - lo));
    rtcCommitGeometry(geom);
    const unsigned id = rtcAttachGeometry(scene_, geom);
    rtcReleaseGeometry(geom);
    device_.check("adding triangle geometry");
    if (id != geometries_.size()) throw std::runtime_error("unexpected Embree geometry id");
    triangles_ += static_cast<int64_t>(triangles.size());
    geometries_.push_back(std::move(info));
    return id;
}

void TubeAccel::commit() {
    rtcCommitScene(scene_);
    device_.check("building the BVH");
    committed_ = true;
}

double TubeAccel::boundingRadius() const {
    if (!committed_ || geometries_.empty()) return 0.0;
    RTCBounds b;
    rtcGetSceneBounds(scene_, &b);
    const Vec3 extent(b.upper_x - b.lower_x, b.upper_y - b.lower_y, b.upper_z - b.lower_z);
    return std::isfinite(length(extent)) ? 0.5 * length(extent) : 0.0;
}

bool TubeAccel::intersect(const Vec3& org, const Vec3& dir, double tMax, const TubeId& origin,
                          TubeHit* hit) const {
    OriginContext ctx = makeContext(origin, geometries_);
    RTCRayHit rh;
    initRay(rh, org, dir, tMax);
    rtcIntersect1(scene_, &ctx.context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;

    const GeometryInfo& info = geometries_[rh.hit.geomID];
    hit->t = rh.ray.tfar;
    hit->point = org + dir * hit->t;
    if (info.surface) {
        hit->surface = true;
        hit->id = {rh.hit.geomID, rh.hit.primID};
        hit->material = info.material;
        hit->normal = normalizeAnyLength(Vec3{rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z});
        Vec3 b;
        coordinateSystem(hit->normal, &hit->tangent, &b);
        return true;
    }
    hit->surface = false;
    hit->segment = rh.hit.primID;
    hit->u = rh.hit.u;
    hit->id = {rh.hit.geomID, info.tubeOf(rh.hit.primID)};
    hit->material = info.materialAlong.empty()
                        ? info.material
                        : info.materialAlong[rh.hit.primID - info.tubeFirstSegment[hit->id.tube]];
    hit->tangent = smoothTangent(info, rh.hit.primID, rh.hit.u);
    // Normal: Embree's geometric normal without its component along the
    // tangent (on a cone of varying radius, or on a joint sphere, it has one).
    Vec3 n{rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
    n = n - hit->tangent * dot(n, hit->tangent);
    const double len = length(n);
    if (len > 1e-12 * (std::abs(rh.hit.Ng_x) + std::abs(rh.hit.Ng_y) + std::abs(rh.hit.Ng_z)) &&
        len > 0) {
        hit->normal = n / len;
    } else {
        // Hit exactly on a joint sphere's pole: any normal orthogonal to the tangent.
        Vec3 b;
        coordinateSystem(hit->tangent, &hit->normal, &b);
    }
    return true;
}

TubeHit TubeAccel::exitPoint(const TubeHit& hit, double axial, double around) const {
    const GeometryInfo& info = geometries_.at(hit.id.geometry);
    if (info.surface) throw std::logic_error("TubeAccel::exitPoint on a triangle");
    const uint32_t first = info.tubeFirstSegment[hit.id.tube];
    const uint32_t end = hit.id.tube + 1 < info.tubeFirstSegment.size()
                             ? info.tubeFirstSegment[hit.id.tube + 1]
                             : info.segmentCount;
    // A closed tube's first segment has a neighbour before it (addGeometry).
    const bool closed = info.flags[first] & RTC_CURVE_FLAG_NEIGHBOR_LEFT;
    const auto vertex = [&](uint32_t segment, int k) {
        const float* v = info.vertices + 4 * (static_cast<size_t>(info.indices[segment]) + k);
        return std::pair{Vec3{v[0], v[1], v[2]}, static_cast<double>(v[3])};
    };
    const auto centre = [&](uint32_t segment, double u, double* radius) {
        const auto [p0, r0] = vertex(segment, 0);
        const auto [p1, r1] = vertex(segment, 1);
        *radius = r0 + (r1 - r0) * u;
        return p0 + (p1 - p0) * u;
    };
    // Carries the normal onto the cross-section whose smooth tangent is t:
    // projected onto the plane orthogonal to it.
    const auto carry = [](const Vec3& n, const Vec3& t) {
        const Vec3 projected = n - t * dot(n, t);
        return dot(projected, projected) > 1e-12 ? normalize(projected) : n;
    };

    double radius = 0;
    centre(hit.segment, hit.u, &radius);
    Vec3 normal = hit.normal * std::cos(around) + cross(hit.tangent, hit.normal) * std::sin(around);
    uint32_t segment = hit.segment;
    double u = std::clamp(static_cast<double>(hit.u), 0.0, 1.0);
    double remaining = axial * radius;  // world units, signed
    // Segment by segment; a bound on the steps keeps a degenerate tube finite.
    for (uint32_t step = 0; remaining != 0 && step <= 4 * (end - first) + 4; ++step) {
        const double length = ::weft::length(vertex(segment, 1).first - vertex(segment, 0).first);
        const double available = remaining > 0 ? (1 - u) * length : u * length;
        if (std::abs(remaining) <= available && length > 0) {
            u += remaining / length;
            break;
        }
        remaining -= remaining > 0 ? available : -available;
        const bool forward = remaining > 0;
        if (forward ? segment + 1 < end : segment > first) {
            segment = forward ? segment + 1 : segment - 1;
        } else if (closed) {
            segment = forward ? first : end - 1;
        } else {
            u = forward ? 1.0 : 0.0;  // the end of an open tube
            break;
        }
        u = forward ? 0.0 : 1.0;
        normal = carry(normal, smoothTangent(info, segment, static_cast<float>(u)));
    }
    u = std::clamp(u, 0.0, 1.0);

    TubeHit exit = hit;
    exit.segment = segment;
    exit.u = static_cast<float>(u);
    exit.tangent = smoothTangent(info, segment, exit.u);
    exit.normal = carry(normal, exit.tangent);
    exit.point = centre(segment, u, &radius) + exit.normal * radius;
    if (!info.materialAlong.empty()) exit.material = info.materialAlong[segment - first];
    return exit;
}

bool TubeAccel::occluded(const Vec3& org, const Vec3& dir, double tMax,
                         const TubeId& origin) const {
    OriginContext ctx = makeContext(origin, geometries_);
    RTCRay ray;
    initRay(ray, org, dir, tMax);
    rtcOccluded1(scene_, &ctx.context, &ray);
    // Embree sets tfar to -inf when the ray is occluded.
    return ray.tfar < 0.0f;
}

}  // namespace weft::render
