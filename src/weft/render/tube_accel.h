// weft/render/tube_accel.h — ray queries against the tubes of a cloth scene (Embree 3).
//
// Every ply (neural mode) or every ply's bundle of fibers (fiber mode) is one
// Embree geometry of round linear curves (cones joined by spheres, with the
// neighbour flags so that joints are hit once); each tube of a geometry is a
// run of consecutive segments. A hit reports the tube it is on and the
// shading geometry: a smooth tangent and Embree's geometric normal, made
// orthogonal to it, as the outward normal. The tangent is that of the curve
// the segments sample, not the segment's own direction, which jumps at every
// joint and draws a fiber's highlight as facets (issue 47): at each vertex
// the central difference of its neighbours (at a tube's open end, the end
// tangent of the parabola through its last three points), interpolated
// linearly along the segment by Embree's curve parameter u and normalized
// (as Phong interpolates normals).
//
// Self-intersection (docs/design.md 7): a ray that leaves a tube (reflected,
// transmitted, or a shadow ray) carries that tube as its origin, and an
// intersection filter drops, on that one tube only,
//   - hits closer than kSelfHitDistance times the tube radius (the surface the
//     ray starts on, whichever way it goes), and
//   - hits where the ray leaves the tube (dir . Ng > 0): a ray entering the
//     tube passes through its interior, whose light transport the yarn model
//     (M, T) or the far-field fiber model already accounts for.
// A later entry into the same tube (a knit loop coming back) is a real hit.
//
// Triangles (the scene's objects, scene_objects.h) share the scene: a hit on
// one reports its triangle as the "tube" of its TubeId, surface = true, the
// unit geometric normal as normal (either side: the materials are
// two-sided) and a tangent orthogonal to it. A ray leaving a triangle drops
// every hit on that triangle (a plane cannot be met again) and hits on its
// geometry closer than kSurfaceSelfHit times the geometry's size.
#pragma once

#include <embree3/rtcore.h>

#include <array>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <vector>

#include "weft/core/embree.h"
#include "weft/core/vec.h"
#include "weft/render/yarn_geometry.h"

namespace weft::render {

inline constexpr uint32_t kNoTube = 0xFFFFFFFFu;

// The tube a ray starts on (geometry id and tube within it), or none.
struct TubeId {
    uint32_t geometry = kNoTube;
    uint32_t tube = kNoTube;
    bool valid() const { return geometry != kNoTube; }
    bool operator==(const TubeId&) const = default;
};

struct TubeHit {
    double t = 0;
    Vec3 point;    // org + t dir
    Vec3 tangent;  // unit segment direction
    Vec3 normal;   // unit, orthogonal to tangent, pointing out of the tube
    TubeId id;
    int material = -1;     // as given to addGeometry or addTriangles
    bool surface = false;  // a triangle of an object, not a tube
    // Where on the tube: the segment (Embree's primID within the geometry)
    // and the curve parameter along it, in [0, 1] (exitPoint walks from them).
    uint32_t segment = 0;
    float u = 0;
};

class TubeAccel {
  public:
    // Fraction of the tube radius below which hits on the origin tube are dropped.
    static constexpr double kSelfHitDistance = 1e-2;

    TubeAccel();
    ~TubeAccel();
    TubeAccel(const TubeAccel&) = delete;
    TubeAccel& operator=(const TubeAccel&) = delete;

    // Adds one geometry holding `tubes` (copied into Embree's buffers; the
    // caller may free them), shaded with `material`. Returns its geometry id.
    // materialAlongTubes: empty, or the material of each segment index along
    // the tubes (segment k of every tube gets element k; every tube must have
    // that many segments: a ply and its fibers share their sample indices),
    // for yarns whose colour varies along the curve; `material` is then
    // only the geometry's record (GeometryInfo::material), no hit reports it.
    uint32_t addGeometry(const std::vector<Tube>& tubes, int material,
                         std::vector<int> materialAlongTubes = {});
    // Adds one triangle mesh (world vertices and index triples, copied),
    // shaded with `material`. Returns its geometry id.
    static constexpr double kSurfaceSelfHit = 1e-7;
    uint32_t addTriangles(const std::vector<Vec3>& vertices,
                          const std::vector<std::array<uint32_t, 3>>& triangles, int material);
    // The material a geometry's hits report (weft view's colour change):
    // its `material`; a geometry with materials along its tubes keeps them.
    int material(uint32_t geometry) const { return geometries_.at(geometry).material; }
    void setMaterial(uint32_t geometry, int material) {
        GeometryInfo& info = geometries_.at(geometry);
        if (!info.materialAlong.empty())
            throw std::logic_error("TubeAccel::setMaterial: materials along its tubes");
        info.material = material;
    }
    // Builds the BVH; call once after the last addGeometry.
    void commit();

    // Nearest hit in (0, tMax) of the ray (org, unit dir) leaving `origin`.
    bool intersect(const Vec3& org, const Vec3& dir, double tMax, const TubeId& origin,
                   TubeHit* hit) const;
    // Whether anything blocks the ray in (0, tMax).
    bool occluded(const Vec3& org, const Vec3& dir, double tMax, const TubeId& origin) const;

    // Where light that entered the tube at `hit` leaves it when it moved
    // `axial` tube radii along the tube (positive along hit.tangent) and
    // turned `around` radians about it (positive from hit.normal towards
    // hit.tangent x hit.normal) (issue 47, docs/exit-point.md): the centre
    // line is walked segment by segment by axial x the tube's radius at the
    // hit, the hit's normal turned by `around` and carried along without
    // twisting (projected onto each new cross-section, a discrete
    // rotation-minimising frame), and the point put on the tube's surface
    // there. An open tube's walk stops at its end (the light leaves at the
    // last cross-section: a short tube or the end of one gives a finite
    // point); a closed tube's wraps round. The result is a hit on the same
    // tube (with the material there, for a tube coloured along its length):
    // point, smooth tangent, normal, segment and u.
    TubeHit exitPoint(const TubeHit& hit, double axial, double around) const;

    int64_t tubeCount() const { return tubes_; }
    int64_t segmentCount() const { return segments_; }
    int64_t triangleCount() const { return triangles_; }
    size_t geometryCount() const { return geometries_.size(); }
    // Bytes Embree holds (geometry buffers + BVH), from its memory monitor.
    int64_t embreeBytes() const { return device_.allocatedBytes(); }
    int64_t embreePeakBytes() const { return device_.peakBytes(); }
    // Radius of the sphere around the committed geometry's bounding box (0
    // for an empty scene): the scene radius of Light::power.
    double boundingRadius() const;

    // Per-geometry facts the intersection filter needs (public for the filter).
    struct GeometryInfo {
        int material = -1;
        bool surface = false;                    // triangles (addTriangles)
        float surfaceSelfHit = 0;                // triangles: kSurfaceSelfHit x the mesh's diagonal
        std::vector<int> materialAlong;          // empty, or per segment index along a tube
        std::vector<uint32_t> tubeFirstSegment;  // ascending; segment -> tube by binary search
        uint32_t segmentCount = 0;
        std::vector<float> tubeRadius;  // largest radius of each tube
        // Embree's buffers (owned by the geometry the scene holds), for the hit tangent.
        const float* vertices = nullptr;    // x, y, z, r per vertex
        const unsigned* indices = nullptr;  // first vertex of each segment
        const unsigned char* flags = nullptr;  // RTC_CURVE_FLAG_NEIGHBOR_* of each segment
        uint32_t tubeOf(uint32_t segment) const;
    };

    // The smooth shading tangent on `segment` at curve parameter u (see the top).
    static Vec3 smoothTangent(const GeometryInfo& info, uint32_t segment, float u);

  private:
    EmbreeDevice device_;
    RTCScene scene_ = nullptr;
    std::vector<GeometryInfo> geometries_;
    int64_t tubes_ = 0, segments_ = 0, triangles_ = 0;
    bool committed_ = false;
};

}  // namespace weft::render
