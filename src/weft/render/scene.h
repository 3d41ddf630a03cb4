// weft/render/scene.h — a scene file turned into what the path tracer needs (issue 7).
//
// Scene builds, from a SceneDesc (scene_file.h) and a mode:
//   - the camera (camera.h: a pinhole, pbrt's perspective camera);
//   - the lights (lights.h; none given: the procedural sky);
//   - the geometry (tube_accel.h) from each yarn's curves (yarn_geometry.h):
//       neural mode: one tube per ply, shaded with the YarnBsdf of the
//         yarn's model (docs/design.md 7);
//       fiber mode: the plies filled with the model's fibers (N, rho, alpha
//         from its "ply" block; generatePly seeded per ply by the yarn,
//         curve and ply index, so the fibers do not change with the render
//         seed), shaded with the model's FiberBcsdf;
//   - the materials, one per distinct model file and colour (a yarn's
//     "colour", or each colour along a yarn with "vertex_colours": a segment
//     then carries its material, tube_accel.h); in neural mode YarnBsdfs
//     built with `yarnOptions` (the sampling ablation of paper Fig. 5).
// Fiber geometry is generated ply by ply and handed to Embree at once, so the
// peak memory is Embree's copy plus one ply's fibers.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "weft/core/bsdf.h"
#include "weft/core/vec.h"
#include "weft/render/camera.h"
#include "weft/render/curve_report.h"
#include "weft/render/curves.h"
#include "weft/render/lights.h"
#include "weft/render/scene_file.h"
#include "weft/render/tube_accel.h"
#include "weft/yarn/yarn_bsdf.h"

namespace weft::render {

// How yarns are drawn and shaded: neural (plies as curves, the fitted yarn
// BSDF), fiber (every fiber, the fiber BCSDF: the ground truth) or dual (plies
// as curves, the dual-scattering baseline after ZMA23, yarn/dual_scattering.h).
enum class RenderMode { Neural, Fiber, Dual };
// Whether the mode draws each ply as one curve (neural, dual) rather than its fibers.
constexpr bool drawsPlies(RenderMode mode) { return mode != RenderMode::Fiber; }

// Largest number of curve segments a scene may hand to Embree (about 60
// bytes each with the BVH): an InputError naming the yarn beyond it.
inline constexpr int64_t kMaxSceneSegments = int64_t{200} * 1000 * 1000;
// Largest number of materials (distinct model files and colours) a scene may
// have: an InputError naming the yarn entry beyond it. A neural material
// costs about 0.4 s and 0.5 MB to build (its energy guard and sampling table).
inline constexpr int kMaxSceneMaterials = 256;
const char* renderModeName(RenderMode mode);
// "neural", "fiber" or "dual"; otherwise an InputError naming `field`.
RenderMode parseRenderMode(const std::string& name, const std::string& field = "--mode");

// The overlap check of one yarn entry (curve_report.h): its curves file, as
// the scene names it, and how much of it lies inside the scene's yarns.
struct YarnEntryOverlap {
    std::string curves;
    YarnOverlap overlap;
};

// The overlap check of a scene's yarn entries, whose curves (in file units)
// `curveSets` holds in the same order: every entry's curves times its scale
// at its radius ("radius", or else the mean of the file's per-point radii
// times the scale) against all of them. Empty when an entry has neither (the
// geometry build refuses that yarn). Cheap next to the build: a hierarchy
// over the control polygons' segments.
std::vector<YarnEntryOverlap> checkYarnOverlap(const SceneDesc& desc,
                                               const std::vector<CurveSet>& curveSets);
// The warnings (yarnOverlapWarning) of the entries that overlap, naming the
// scene file `sceneName`.
std::vector<std::string> yarnOverlapWarnings(const std::string& sceneName,
                                             const std::vector<YarnEntryOverlap>& overlaps);
// The "yarn_overlap" list of IMAGE.json: toJson(overlap, i, curves) per entry.
nlohmann::json yarnOverlapJson(const std::vector<YarnEntryOverlap>& overlaps);

struct SceneBuildStats {
    int64_t curves = 0;           // yarn curves read
    int64_t curvePoints = 0;      // their control points
    int64_t tubes = 0;            // plies (neural) or fibers (fiber)
    int64_t segments = 0;         // round linear curve segments handed to Embree
    int64_t embreeBytes = 0;      // geometry + BVH after the build (memory monitor)
    int64_t embreePeakBytes = 0;  // largest Embree allocation during the build
    int64_t materials = 0;        // distinct (model, colour) BSDFs
    int64_t materialBytes = 0;    // the materials' BSDFs (yarn: networks and tables)
    double seconds = 0;           // building time, model loading included
    // Per yarn entry, the overlap check (checkYarnOverlap; empty when it could not run).
    std::vector<YarnEntryOverlap> yarnOverlap;
};

class Scene {
  public:
    Scene(const SceneDesc& desc, RenderMode mode, bool quiet = true,
          const YarnBsdfOptions& yarnOptions = {});

    RenderMode mode() const { return mode_; }
    const Camera& camera() const { return camera_; }
    int width() const { return width_; }
    int height() const { return height_; }
    const TubeAccel& accel() const { return *accel_; }
    const std::vector<std::unique_ptr<Light>>& lights() const { return lights_; }
    const SceneBuildStats& stats() const { return stats_; }

    // BSDF of a hit's material (TubeHit::material): the YarnBsdf (neural
    // mode) or the FiberBcsdf (fiber mode) of its model.
    const Bsdf& bsdf(int material) const { return *bsdfs_[material]; }
    // The local frame of that BSDF at a hit: in neural mode the yarn frame
    // (t, t x n, n) of docs/design.md 2, in fiber mode the fiber frame with the
    // tangent as +x (fiber_bcsdf.h).
    Frame shadingFrame(const TubeHit& hit) const {
        return drawsPlies(mode_) ? yarnFrame(hit.tangent, hit.normal) : Frame::fromX(hit.tangent);
    }

  private:
    RenderMode mode_;
    Camera camera_;
    int width_, height_;
    std::unique_ptr<TubeAccel> accel_;
    std::vector<std::unique_ptr<Light>> lights_;
    std::vector<std::unique_ptr<Bsdf>> bsdfs_;  // one per material
    SceneBuildStats stats_;
};

}  // namespace weft::render
