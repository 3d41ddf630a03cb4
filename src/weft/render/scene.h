// weft/render/scene.h — a scene file turned into what the path tracer needs (issue 7).
//
// Scene builds, from a SceneDesc (scene_file.h) and SceneOptions:
//   - the camera (camera.h: a pinhole, pbrt's perspective camera);
//   - the lights (light.h, each made by its registered type; none given: the
//     procedural sky);
//   - the geometry (tube_accel.h) from each yarn's curves (yarn_geometry.h),
//     as the yarn's drawing mode (yarn_mode.h) says:
//       plies (neural, dual): one tube per ply, shaded in the yarn frame;
//       fibers (fiber): the plies filled with the model's fibers (N, rho,
//         alpha from its "ply" block; generatePly seeded per ply by the yarn,
//         curve and ply index, so the fibers do not change with the render
//         seed), each shaded in its fiber frame;
//   - the materials, one per distinct model file, colour and mode (a yarn's
//     "colour", or each colour along a yarn with "vertex_colours": a segment
//     then carries its material, tube_accel.h), each with the BSDF its mode
//     makes; neural ones built with `options.yarn` (the sampling ablation of
//     paper Fig. 5).
// Fiber geometry is generated ply by ply and handed to Embree at once, so the
// peak memory is Embree's copy plus one ply's fibers.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "weft/core/bsdf.h"
#include "weft/core/vec.h"
#include "weft/render/camera.h"
#include "weft/render/curve_report.h"
#include "weft/render/curves.h"
#include "weft/render/light.h"
#include "weft/render/scene_file.h"
#include "weft/render/tube_accel.h"
#include "weft/render/yarn_geometry.h"
#include "weft/render/yarn_mode.h"
#include "weft/yarn/yarn_bsdf.h"

namespace weft::render {

// Largest number of curve segments a scene may hand to Embree (about 60
// bytes each with the BVH): an InputError naming the yarn beyond it.
inline constexpr int64_t kMaxSceneSegments = int64_t{200} * 1000 * 1000;
// Largest number of materials (distinct model files and colours) a scene may
// have: an InputError naming the yarn entry beyond it. A neural material
// costs about 0.4 s and 0.5 MB to build (its energy guard and sampling table).
inline constexpr int kMaxSceneMaterials = 256;
// Largest number of objects (scene_objects.h) a scene may have.
inline constexpr size_t kMaxSceneObjects = 1024;

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
    int64_t objects = 0;          // floors, backdrops, meshes (scene_objects.h)
    int64_t triangles = 0;        // their triangles
    int64_t embreeBytes = 0;      // geometry + BVH after the build (memory monitor)
    int64_t embreePeakBytes = 0;  // largest Embree allocation during the build
    int64_t materials = 0;        // distinct (model, colour) BSDFs
    int64_t materialBytes = 0;    // the materials' BSDFs (yarn: networks and tables)
    double seconds = 0;           // building time, model loading included
    // Per yarn entry, the overlap check (checkYarnOverlap; empty when it could not run).
    std::vector<YarnEntryOverlap> yarnOverlap;
    // The yarn entries with an "appearance" and the C_TT found for each.
    struct AppearanceColour {
        size_t yarn = 0;
        Rgb appearance;  // sRGB, as the scene gives it
        Rgb cTT;         // the fiber colour every mode draws the yarn with
    };
    std::vector<AppearanceColour> appearanceColours;
};

// One line per yarn entry with an "appearance": the C_TT it is drawn with
// ("scene.json: yarns[2]: appearance (sRGB 0.85, 0.55, 0.3) is C_TT ...").
std::vector<std::string> appearanceNotes(const std::string& sceneName,
                                         const SceneBuildStats& stats);
// The "appearance" list of IMAGE.json: {"yarn", "appearance" (sRGB), "c_tt"} per entry.
nlohmann::json appearanceJson(const SceneBuildStats& stats);

// A yarn material's identity: its model (file, and a family yarn's
// parameters), its colour (empty: the model's own) and its drawing mode.
using MaterialKey = std::tuple<std::string, std::vector<double>, std::string>;

struct SceneOptions {
    // A drawing mode for every yarn (a registered name, yarn_mode.h), over
    // the yarns' own "mode"; empty: each yarn's own (neural where it has none).
    std::string mode;
    bool quiet = true;     // no progress bar
    YarnBsdfOptions yarn;  // the neural mode's yarn BSDF
};

class Scene {
  public:
    explicit Scene(const SceneDesc& desc, const SceneOptions& options = {});

    // What weft view changes without building the geometry again (issue 44):
    // the camera and film of `desc` (checked as the constructor checks them),
    // and its lights. Not while a render of this scene runs.
    void setView(const SceneDesc& desc);
    void setLights(const SceneDesc& desc);
    // The yarns' colours ("colour", "appearance") of `desc`, whose yarn
    // entries are otherwise the constructor's (curves, model, mode: the
    // caller's to ensure; weft view compares the scene files), none of them
    // vertex-coloured: materials whose model, colour and mode recur are
    // kept, the others built, the geometry kept. On an InputError (a colour
    // the model refuses) the scene is as it was. `draft`: the new materials
    // are their modes' drafts (YarnMode::makeDraftBsdf: the same values,
    // built faster, sampled more coarsely) until finishMaterials(); without
    // it every material ends final, kept drafts included.
    void setYarnColours(const SceneDesc& desc, bool draft = false);
    // Every draft material made final: the scene then renders bit for bit
    // what a scene built afresh renders. Cheap when there is none.
    void finishMaterials();

    // The drawing mode of every yarn, or "mixed" when they differ (neural for
    // a scene without yarns).
    const std::string& modeName() const { return modeName_; }
    const Camera& camera() const { return camera_; }
    int width() const { return width_; }
    int height() const { return height_; }
    const TubeAccel& accel() const { return *accel_; }
    const std::vector<std::unique_ptr<Light>>& lights() const { return lights_; }
    // Which light NEE samples, and with what probability (light_sampler.h).
    const LightSampler& lightSampler() const { return lightSampler_; }
    const SceneBuildStats& stats() const { return stats_; }

    // BSDF of a hit's material (TubeHit::material), as its yarn's mode made
    // it: the YarnBsdf (neural), DualScatteringBsdf (dual) or FiberBcsdf
    // (fiber) of its model.
    const Bsdf& bsdf(int material) const { return *bsdfs_[material]; }
    // Whether any material's BSDF batches faster (Bsdf::batchesFaster: the
    // neural mode's yarn BSDF).
    bool batchesFaster() const {
        for (const auto& b : bsdfs_)
            if (b->batchesFaster()) return true;
        return false;
    }
    // What a geometry of the accel draws, for the yarn_id pass: yarn entry i
    // as i + 1, object j as -(j + 1); 0 for none (kNoTube).
    int passId(uint32_t geometry) const {
        return geometry < passIds_.size() ? passIds_[geometry] : 0;
    }
    // The local frame of that BSDF at a hit: for plies the yarn frame (t, t x
    // n, n) of docs/design.md 2, for fibers the fiber frame with the tangent as
    // +x (fiber_bcsdf.h).
    Frame shadingFrame(const TubeHit& hit) const {
        if (hit.surface) return Frame::fromZ(hit.normal);  // surface_bsdf.h: z is the normal
        return plyFrame_[hit.material] ? yarnFrame(hit.tangent, hit.normal)
                                       : Frame::fromX(hit.tangent);
    }

  private:
    SceneOptions options_;
    std::string modeName_;
    Camera camera_;
    int width_ = 0, height_ = 0;
    std::unique_ptr<TubeAccel> accel_;
    std::vector<std::unique_ptr<Light>> lights_;
    LightSamplerDesc lightSamplerDesc_;
    LightSampler lightSampler_;
    void createLights(const SceneDesc& desc);   // lights_ and the sampler's description
    void buildLightSampler();                   // lightSampler_ of them and the geometry
    std::vector<std::unique_ptr<Bsdf>> bsdfs_;  // one per material
    std::vector<uint8_t> plyFrame_;             // per material: its mode draws plies
    std::vector<int> passIds_;                  // per accel geometry (passId)
    // The yarns' materials come first in bsdfs_, these keys theirs; the
    // objects' follow.
    std::vector<MaterialKey> materialKeys_;
    size_t yarnMaterials_ = 0;
    std::vector<int> entryMaterial_;  // per yarn entry; -1: vertex-coloured
    SceneBuildStats stats_;

    // stats_'s material count and bytes, from bsdfs_.
    void countMaterials();
};

// The plies of curve `curveIndex` of a yarn entry, framed at the sampling
// step its drawing mode needs (sampleStep: fibers == nullptr for neural and
// dual mode, the model's ply block for fiber mode): what the scene builds
// and what `weft scene export --fibers` writes. InputError as frameCurve.
std::vector<FramedCurve> yarnPlyCurves(const Curve& curve, const YarnDesc& yarn,
                                       const PlyParams* fibers, size_t curveIndex);

// The seed of the fibers of ply j of curve c of yarn entry y in the scene's
// fiber arrangement `arrangement` (render.fiber_seed): where the ply is, not
// the render's seed (a fiber render's geometry is the same at every seed).
// Arrangement 0 is the one every earlier version drew.
uint64_t fiberSeed(size_t y, size_t c, size_t j, uint64_t arrangement);

}  // namespace weft::render
