#include "weft/render/scene.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <tuple>

#include "weft/core/error.h"
#include "weft/core/image.h"
#include "weft/core/json_message.h"
#include "weft/core/limits.h"
#include "weft/core/math.h"
#include "weft/core/progress.h"
#include "weft/core/rng.h"
#include "weft/render/curves.h"
#include "weft/render/environment_light.h"
#include "weft/render/yarn_geometry.h"
#include "weft/yarn/family_model.h"
#include "weft/yarn/yarn_appearance.h"
#include "weft/yarn/yarn_model.h"

namespace weft::render {

namespace {

// The largest radius a yarn curve is drawn with (for the sampling step).
double largestRadius(const Curve& curve, const YarnDesc& yarn) {
    if (yarn.radius) return *yarn.radius;
    if (curve.radii.empty()) return 0;  // frameCurve reports the missing radii
    return yarn.scale *
           static_cast<double>(*std::max_element(curve.radii.begin(), curve.radii.end()));
}

// What the geometry costs per segment: Embree's curve and BVH (about 60
// bytes), the tube's own copy and the framed curve it came from.
constexpr double kBytesPerSegment = 160;

std::string geometryName(const SceneDesc& desc, size_t yarn, const YarnMode& mode) {
    return (desc.path.empty() ? std::string("scene") : desc.path) + ": yarns[" +
           std::to_string(yarn) + "] (" + desc.yarns[yarn].curves + "): the " + mode.name() +
           " geometry up to this yarn";
}

// Every curve point, times the yarn's scale, within kMaxSceneCoordinate
// (scene_file.h): Embree works in float.
void checkCurveExtent(const CurveSet& set, const SceneDesc& desc, size_t yarn) {
    const double limit = kMaxSceneCoordinate / desc.yarns[yarn].scale;
    for (size_t c = 0; c < set.curves.size(); ++c) {
        const std::vector<Vec3>& points = set.curves[c].points;
        for (size_t k = 0; k < points.size(); ++k) {
            const Vec3& p = points[k];
            if (std::fabs(p.x) <= limit && std::fabs(p.y) <= limit && std::fabs(p.z) <= limit)
                continue;
            std::ostringstream msg;
            msg << (desc.path.empty() ? std::string("scene") : desc.path) << ": yarns[" << yarn
                << "] (" << desc.yarns[yarn].curves << "): curve " << c << ", point " << k << " ("
                << formatNumber(p.x) << ", " << formatNumber(p.y) << ", " << formatNumber(p.z)
                << ") times scale " << formatNumber(desc.yarns[yarn].scale)
                << " is out of range: allowed coordinates within +-" << kMaxSceneCoordinate
                << " scene units";
            throw InputError(msg.str());
        }
    }
}

[[noreturn]] void tooMuchGeometry(const SceneDesc& desc, size_t yarn, const YarnMode& mode) {
    throw InputError((desc.path.empty() ? std::string("scene") : desc.path) + ": yarns[" +
                     std::to_string(yarn) + "] (" + desc.yarns[yarn].curves + "): the " +
                     mode.name() + " geometry would exceed " +
                     std::to_string(kMaxSceneSegments) +
                     " curve segments (about 60 bytes each in Embree); use fewer or shorter "
                     "curves, or a larger radius");
}

// The segments frameCurve and the mode will make of `curve` of the entry
// `yarn`, from its control polygon's length (to within the spline's bulge),
// before any is allocated.
double estimatedSegments(const Curve& curve, const YarnDesc& yarn, const YarnMode& mode,
                         const PlyParams& fibers) {
    const double radius = largestRadius(curve, yarn);
    const double step = sampleStep(radius > 0 ? radius : 1.0, yarn.plies, yarn.plyTwist,
                                   mode.drawsPlies() ? nullptr : &fibers);
    double chord = 0;
    const std::vector<Vec3>& cp = curve.points;
    for (size_t k = 0; k + 1 < cp.size(); ++k) chord += length(cp[k + 1] - cp[k]);
    if (curve.closed && cp.size() > 1) chord += length(cp.front() - cp.back());
    return (chord * yarn.scale / step + 1) * yarn.plies * (mode.drawsPlies() ? 1 : fibers.fibers);
}

// Refuses, naming the entry, geometry beyond kMaxSceneSegments or the memory
// budget once `planned` + `estimate` segments are made.
void checkGeometrySize(double planned, double estimate, const SceneDesc& desc, size_t y,
                       const YarnMode& mode) {
    if (planned + estimate > static_cast<double>(kMaxSceneSegments))
        tooMuchGeometry(desc, y, mode);
    checkMemoryBudget((planned + estimate) * kBytesPerSegment, geometryName(desc, y, mode));
}

// The radius the overlap check gives an entry: its "radius", or the mean of
// the per-point radii times its scale; none when a curve has no radii.
std::optional<double> overlapRadius(const YarnDesc& yarn, const CurveSet& set) {
    if (yarn.radius) return *yarn.radius;
    double sum = 0;
    size_t count = 0;
    for (const Curve& c : set.curves) {
        if (c.radii.empty()) return std::nullopt;
        for (float r : c.radii) sum += r;
        count += c.radii.size();
    }
    if (count == 0) return std::nullopt;
    return yarn.scale * sum / static_cast<double>(count);
}

// The materials of a scene: one BSDF per distinct model file, colour and
// drawing mode, built the first time a yarn asks for it (a vertex-coloured
// yarn asks for each of its colours, yarn_geometry.h kColourSteps).
class SceneMaterials {
  public:
    // `reuse`: materials of an earlier build by their keys, moved in instead
    // of built where a key recurs (Scene::setYarnColours).
    SceneMaterials(const SceneDesc& desc, const std::vector<const YarnMode*>& modes,
                   const YarnBsdfOptions& options, std::vector<std::unique_ptr<Bsdf>>* bsdfs,
                   std::vector<uint8_t>* plyFrame, std::vector<MaterialKey>* keys,
                   std::map<MaterialKey, std::unique_ptr<Bsdf>>* reuse = nullptr,
                   bool draft = false)
        : desc_(desc),
          modes_(modes),
          options_(options),
          bsdfs_(bsdfs),
          plyFrame_(plyFrame),
          keys_(keys),
          reuse_(reuse),
          draft_(draft) {}

    // The model of yarn entry y: as its file holds it, or a family model's
    // yarn at the entry's "yarn" (docs/family.md); each file read once, each
    // family yarn made once.
    const YarnModel& model(size_t y) {
        const YarnDesc& yarn = desc_.yarns[y];
        const std::string key = modelKey(y);
        auto it = models_.find(key);
        if (it != models_.end()) return it->second;
        auto file = files_.find(yarn.model);
        if (file == files_.end())
            file = files_.emplace(yarn.model, ModelFile::load(yarn.model)).first;
        const std::string yarnHint =
            "in \"yarn\" ({\"fibers\", \"density\", \"twist\", \"beta_r_deg\", "
            "\"beta_tt_deg\", \"gamma_tt_deg\", \"c_r\"})";
        return models_
            .emplace(key, file->second.forYarn(yarn.yarn, entryName(y), entryName(y) + ".yarn",
                                               yarnHint))
            .first->second;
    }

    // The C_TT that makes yarn entry y look its "appearance"
    // (appearance_table.h): by its model's table, or by one computed once per
    // model file for a colour model written before the table existed.
    Rgb appearanceColour(size_t y) {
        const YarnDesc& yarn = desc_.yarns[y];
        const YarnModel& m = model(y);
        const std::string what = entryName(y) + ".appearance";
        if (!m.colour)
            throw InputError(what + ": " + yarn.model +
                             " is fitted for one colour; colour by appearance needs a colour "
                             "model (models/MATERIAL-colour.json, or weft fit --colour-range)");
        auto it = tables_.find(modelKey(y));
        if (it == tables_.end())
            it = tables_
                     .emplace(modelKey(y),
                              m.appearance ? *m.appearance : computeAppearanceTable(m, yarn.model))
                     .first;
        const Rgb& srgb = *yarn.appearance;
        return it->second.cTTFor(srgbToLinear(srgb), what);
    }

    // The material of yarn entry y (not vertex-coloured) in its "colour", or
    // in the C_TT of its "appearance", which `appearances` records.
    int ownMaterial(size_t y, std::vector<SceneBuildStats::AppearanceColour>* appearances) {
        const YarnDesc& yarn = desc_.yarns[y];
        std::optional<Rgb> colour = yarn.colour;
        if (yarn.appearance) {
            colour = appearanceColour(y);
            appearances->push_back({y, *yarn.appearance, *colour});
        }
        return material(y, colour);
    }

    // The material of yarn entry y in `colour` (none: the model's own).
    int material(size_t y, const std::optional<Rgb>& colour) {
        const YarnDesc& yarn = desc_.yarns[y];
        const YarnMode& mode = *modes_[y];
        if (colour && last_ && last_->y == y && last_->colour == *colour) return last_->material;
        const std::vector<double> colourKey =
            colour ? std::vector<double>{colour->r, colour->g, colour->b} : std::vector<double>{};
        const MaterialKey key{modelKey(y), colourKey, mode.name()};
        auto [it, inserted] = index_.try_emplace(key, 0);
        if (inserted) {
            if (bsdfs_->size() >= static_cast<size_t>(kMaxSceneMaterials))
                throw InputError(entryName(y) + ": more than " + std::to_string(kMaxSceneMaterials) +
                                 " materials (distinct models, colours and modes) in the scene; "
                                 "give fewer distinct colours");
            it->second = static_cast<int>(bsdfs_->size());
            std::unique_ptr<Bsdf> bsdf;
            if (reuse_)
                if (auto old = reuse_->find(key); old != reuse_->end()) {
                    bsdf = std::move(old->second);
                    reuse_->erase(old);
                }
            if (!bsdf) {
                const std::string what =
                    entryName(y) + (yarn.vertexColours.empty() ? ".colour" : ".vertex_colours");
                bsdf = draft_ ? mode.makeDraftBsdf(model(y), colour, yarn.model, what, options_)
                              : mode.makeBsdf(model(y), colour, yarn.model, what, options_);
            }
            bsdfs_->push_back(std::move(bsdf));
            plyFrame_->push_back(mode.drawsPlies());
            keys_->push_back(key);
        }
        if (colour) last_ = Last{y, *colour, it->second};
        return it->second;
    }

  private:
    // A model's key: its file, and a family yarn's parameters.
    std::string modelKey(size_t y) const {
        const YarnDesc& yarn = desc_.yarns[y];
        return yarn.yarn ? yarn.model + "\n" + yarn.yarn->toJson().dump() : yarn.model;
    }

    std::string entryName(size_t y) const {
        return (desc_.path.empty() ? std::string("scene") : desc_.path) + ": yarns[" +
               std::to_string(y) + "]";
    }

    const SceneDesc& desc_;
    const std::vector<const YarnMode*>& modes_;
    YarnBsdfOptions options_;
    std::vector<std::unique_ptr<Bsdf>>* bsdfs_;
    std::vector<uint8_t>* plyFrame_;
    std::vector<MaterialKey>* keys_;
    std::map<MaterialKey, std::unique_ptr<Bsdf>>* reuse_;
    bool draft_;  // new materials as their modes' drafts
    std::map<std::string, YarnModel> models_;
    std::map<std::string, ModelFile> files_;  // by path
    std::map<std::string, AppearanceTable> tables_;
    std::map<MaterialKey, int> index_;
    // The last coloured lookup: neighbouring segments mostly share a colour.
    struct Last {
        size_t y;
        Rgb colour;
        int material;
    };
    std::optional<Last> last_;
};

// The drawing mode of each yarn entry: the override, else its own, else the default.
std::vector<const YarnMode*> entryModes(const SceneDesc& desc, const std::string& override) {
    std::vector<const YarnMode*> modes;
    const YarnMode* all = override.empty() ? nullptr : &yarnModeNamed(override);
    for (const YarnDesc& yarn : desc.yarns)
        modes.push_back(all                  ? all
                        : yarn.mode.empty()  ? &defaultYarnMode()
                                             : &yarnModeNamed(yarn.mode, "yarns[].mode"));
    return modes;
}

// One name for the scene's modes: the override, the one every yarn has, or "mixed".
std::string modesName(const std::vector<const YarnMode*>& modes, const std::string& override) {
    if (!override.empty()) return yarnModeNamed(override).name();
    if (modes.empty()) return defaultYarnMode().name();
    for (const YarnMode* m : modes)
        if (m != modes.front()) return "mixed";
    return modes.front()->name();
}

}  // namespace

std::vector<YarnEntryOverlap> checkYarnOverlap(const SceneDesc& desc,
                                               const std::vector<CurveSet>& curveSets) {
    std::vector<YarnCurves> yarns;
    for (size_t y = 0; y < desc.yarns.size(); ++y) {
        const std::optional<double> radius = overlapRadius(desc.yarns[y], curveSets[y]);
        if (!radius) return {};
        yarns.push_back({&curveSets[y], desc.yarns[y].scale, *radius});
    }
    const std::vector<YarnOverlap> overlaps =
        yarnOverlaps(yarns, desc.path.empty() ? std::string("scene") : desc.path);
    std::vector<YarnEntryOverlap> result;
    for (size_t y = 0; y < overlaps.size(); ++y)
        result.push_back({desc.yarns[y].curves, overlaps[y]});
    return result;
}

std::vector<std::string> yarnOverlapWarnings(const std::string& sceneName,
                                             const std::vector<YarnEntryOverlap>& overlaps) {
    std::vector<std::string> warnings;
    for (size_t y = 0; y < overlaps.size(); ++y) {
        const std::string w =
            yarnOverlapWarning(sceneName, y, overlaps[y].curves, overlaps[y].overlap);
        if (!w.empty()) warnings.push_back(w);
    }
    return warnings;
}

nlohmann::json yarnOverlapJson(const std::vector<YarnEntryOverlap>& overlaps) {
    nlohmann::json list = nlohmann::json::array();
    for (size_t y = 0; y < overlaps.size(); ++y)
        list.push_back(toJson(overlaps[y].overlap, y, overlaps[y].curves));
    return list;
}

std::vector<std::string> appearanceNotes(const std::string& sceneName,
                                         const SceneBuildStats& stats) {
    std::vector<std::string> notes;
    for (const SceneBuildStats::AppearanceColour& a : stats.appearanceColours)
        notes.push_back((sceneName.empty() ? std::string("scene") : sceneName) + ": yarns[" +
                        std::to_string(a.yarn) + "]: appearance (sRGB " +
                        formatNumber(a.appearance.r) + ", " + formatNumber(a.appearance.g) + ", " +
                        formatNumber(a.appearance.b) + ") is C_TT " + formatNumber(a.cTT.r) + ", " +
                        formatNumber(a.cTT.g) + ", " + formatNumber(a.cTT.b));
    return notes;
}

nlohmann::json appearanceJson(const SceneBuildStats& stats) {
    nlohmann::json list = nlohmann::json::array();
    for (const SceneBuildStats::AppearanceColour& a : stats.appearanceColours)
        list.push_back(
            {{"yarn", a.yarn}, {"appearance", rgbJson(a.appearance)}, {"c_tt", rgbJson(a.cTT)}});
    return list;
}

Scene::Scene(const SceneDesc& desc, const SceneOptions& options)
    : options_(options), accel_(std::make_unique<TubeAccel>()) {
    const auto start = std::chrono::steady_clock::now();
    setView(desc);
    createLights(desc);  // their sampler once the geometry gives the scene's size

    // One material per distinct model file, colour and mode (SceneMaterials).
    const std::vector<const YarnMode*> modes = entryModes(desc, options.mode);
    modeName_ = modesName(modes, options.mode);
    SceneMaterials materials(desc, modes, options.yarn, &bsdfs_, &plyFrame_, &materialKeys_);
    std::vector<CurveSet> curveSets;
    entryMaterial_.assign(desc.yarns.size(), -1);  // -1: vertex-coloured
    for (size_t y = 0; y < desc.yarns.size(); ++y) {
        const YarnDesc& yarn = desc.yarns[y];
        curveSets.push_back(readCurves(yarn.curves));
        if (!yarn.vertexColours.empty()) readVertexColours(yarn.vertexColours, &curveSets.back());
        checkCurveExtent(curveSets.back(), desc, y);
        stats_.curves += static_cast<int64_t>(curveSets.back().curves.size());
        stats_.curvePoints += static_cast<int64_t>(curveSets.back().pointCount());
        // The yarn's own material now, so that its model is checked before any
        // geometry; vertex-coloured yarns get the rest segment by segment below.
        const std::vector<Curve>& read = curveSets.back().curves;
        if (yarn.vertexColours.empty())
            entryMaterial_[y] = materials.ownMaterial(y, &stats_.appearanceColours);
        else if (!read.empty()) materials.material(y, read.front().colours.front());
    }
    // The whole geometry's estimate first: the overlap check samples the
    // yarns at the spacing of the geometry's segments (R / 4 or finer), so
    // its work is bounded by a geometry that may be built (issue 41: a render
    // of 20,000 long random segments spent minutes in the check).
    double estimated = 0;
    for (size_t y = 0; y < desc.yarns.size(); ++y)
        for (const Curve& curve : curveSets[y].curves) {
            const double estimate =
                estimatedSegments(curve, desc.yarns[y], *modes[y], materials.model(y).ply);
            checkGeometrySize(estimated, estimate, desc, y, *modes[y]);
            estimated += estimate;
        }
    // Before the geometry: what the render will draw inside other yarns.
    stats_.yarnOverlap = checkYarnOverlap(desc, curveSets);

    Progress progress("build " + modeName_ + " geometry", static_cast<uint64_t>(stats_.curves),
                      options.quiet);
    int64_t planned = 0;
    for (size_t y = 0; y < desc.yarns.size(); ++y) {
        const YarnDesc& yarn = desc.yarns[y];
        const YarnMode& mode = *modes[y];
        const bool vertexColoured = !yarn.vertexColours.empty();
        const int material = entryMaterial_[y];
        const PlyParams& fibers = materials.model(y).ply;
        const std::vector<Curve>& curves = curveSets[y].curves;
        for (size_t c = 0; c < curves.size(); ++c) {
            // Again with the segments made so far: the spline may bulge.
            checkGeometrySize(static_cast<double>(planned),
                              estimatedSegments(curves[c], yarn, mode, fibers), desc, y, mode);
            const std::vector<FramedCurve> plies =
                yarnPlyCurves(curves[c], yarn, mode.drawsPlies() ? nullptr : &fibers, c);
            for (size_t j = 0; j < plies.size(); ++j) {
                // Refuse before allocating: a fiber-mode scene costs fibers x samples segments.
                const int64_t tubes = mode.drawsPlies() ? 1 : fibers.fibers;
                planned += tubes * static_cast<int64_t>(plies[j].size());
                if (planned > kMaxSceneSegments) tooMuchGeometry(desc, y, mode);
                // A colour per segment: its first sample's (the ply's fibers
                // share its sample indices, so one list serves them all).
                std::vector<int> along;
                if (vertexColoured) {
                    const size_t segments = plies[j].closed ? plies[j].size() : plies[j].size() - 1;
                    along.resize(segments);
                    for (size_t k = 0; k < segments; ++k)
                        along[k] = materials.material(y, plies[j].colours[k]);
                }
                const int first = vertexColoured ? along.front() : material;
                uint32_t id = kNoTube;
                if (mode.drawsPlies()) {
                    id = accel_->addGeometry({toTube(plies[j])}, first, std::move(along));
                } else {
                    id = accel_->addGeometry(
                        fiberTubes(plies[j], fibers, fiberSeed(y, c, j, desc.render.fiberSeed)),
                        first, std::move(along));
                }
                if (id != kNoTube) passIds_.push_back(static_cast<int>(y) + 1);
            }
            progress.add();
        }
    }
    // The objects: each its triangles and its own material.
    if (desc.objects.size() > kMaxSceneObjects)
        throw InputError((desc.path.empty() ? std::string("scene") : desc.path) + ": " +
                         std::to_string(desc.objects.size()) + " objects: allowed at most " +
                         std::to_string(kMaxSceneObjects) + " (join meshes into one OBJ file)");
    int64_t triangles = 0;
    for (size_t i = 0; i < desc.objects.size(); ++i) {
        const std::string what = (desc.path.empty() ? std::string("scene") : desc.path) +
                                 ": objects[" + std::to_string(i) + "]";
        Triangles t;
        try {
            t = objectTriangles(desc.objects[i]);
        } catch (const InputError& e) {
            throw InputError(what + ": " + e.what());
        }
        triangles += static_cast<int64_t>(t.indices.size());
        if (triangles > kMaxSceneTriangles)
            throw InputError(what + ": the objects hold more than " +
                             std::to_string(kMaxSceneTriangles) +
                             " triangles, the most a scene takes");
        const int material = static_cast<int>(bsdfs_.size());
        bsdfs_.push_back(makeSurfaceBsdf(desc.objects[i].material, what + ".material"));
        plyFrame_.push_back(0);
        if (accel_->addTriangles(t.vertices, t.indices, material) != kNoTube)
            passIds_.push_back(-static_cast<int>(i) - 1);
    }
    accel_->commit();
    progress.finish();
    yarnMaterials_ = materialKeys_.size();
    buildLightSampler();  // the power of infinite lights needs the scene's size
    stats_.objects = static_cast<int64_t>(desc.objects.size());
    stats_.triangles = accel_->triangleCount();
    stats_.tubes = accel_->tubeCount();
    stats_.segments = accel_->segmentCount();
    stats_.embreeBytes = accel_->embreeBytes();
    stats_.embreePeakBytes = accel_->embreePeakBytes();
    countMaterials();
    stats_.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void Scene::countMaterials() {
    stats_.materials = static_cast<int64_t>(bsdfs_.size());
    stats_.materialBytes = 0;
    for (const auto& bsdf : bsdfs_)
        stats_.materialBytes += static_cast<int64_t>(bsdf->memoryBytes());
}

void Scene::finishMaterials() {
    for (size_t m = 0; m < yarnMaterials_; ++m) {
        const YarnMode& mode = yarnModeNamed(std::get<2>(materialKeys_[m]));
        if (auto final = mode.finishDraft(*bsdfs_[m], options_.yarn)) bsdfs_[m] = std::move(final);
    }
    countMaterials();
}

void Scene::setYarnColours(const SceneDesc& desc, bool draft) {
    if (desc.yarns.size() != entryMaterial_.size())
        throw std::logic_error("Scene::setYarnColours: another number of yarn entries");
    for (size_t y = 0; y < desc.yarns.size(); ++y)
        if (!desc.yarns[y].vertexColours.empty() || entryMaterial_[y] < 0)
            throw std::logic_error("Scene::setYarnColours: a vertex-coloured yarn");
    // The yarns' materials afresh, those whose key recurs moved over.
    std::map<MaterialKey, std::unique_ptr<Bsdf>> reuse;
    for (size_t m = 0; m < yarnMaterials_; ++m)
        reuse.emplace(materialKeys_[m], std::move(bsdfs_[m]));
    std::vector<std::unique_ptr<Bsdf>> bsdfs;
    std::vector<uint8_t> plyFrame;
    std::vector<MaterialKey> keys;
    std::vector<int> entryMaterial(desc.yarns.size());
    std::vector<SceneBuildStats::AppearanceColour> appearanceColours;
    const std::vector<const YarnMode*> modes = entryModes(desc, options_.mode);
    try {
        SceneMaterials materials(desc, modes, options_.yarn, &bsdfs, &plyFrame, &keys, &reuse,
                                 draft);
        for (size_t y = 0; y < desc.yarns.size(); ++y)
            entryMaterial[y] = materials.ownMaterial(y, &appearanceColours);
    } catch (...) {
        // This scene as it was: the materials not moved yet, and those that were.
        for (size_t m = 0; m < keys.size(); ++m) reuse.emplace(keys[m], std::move(bsdfs[m]));
        for (size_t m = 0; m < yarnMaterials_; ++m)
            bsdfs_[m] = std::move(reuse.at(materialKeys_[m]));
        throw;
    }
    // The objects' materials after them, as the constructor orders them.
    for (size_t m = yarnMaterials_; m < bsdfs_.size(); ++m) {
        bsdfs.push_back(std::move(bsdfs_[m]));
        plyFrame.push_back(plyFrame_[m]);
    }
    const int objectShift = static_cast<int>(keys.size()) - static_cast<int>(yarnMaterials_);
    for (uint32_t g = 0; g < passIds_.size(); ++g)
        accel_->setMaterial(g, passIds_[g] > 0 ? entryMaterial[passIds_[g] - 1]
                                               : accel_->material(g) + objectShift);
    bsdfs_ = std::move(bsdfs);
    plyFrame_ = std::move(plyFrame);
    materialKeys_ = std::move(keys);
    yarnMaterials_ = materialKeys_.size();
    entryMaterial_ = std::move(entryMaterial);
    stats_.appearanceColours = std::move(appearanceColours);
    if (draft)
        countMaterials();
    else
        finishMaterials();  // kept drafts too; counts
}

void Scene::setView(const SceneDesc& desc) {
    // The film: double RGB sums while rendering, then the float image and its
    // EXR and PNG encodings: about 56 bytes per pixel.
    checkMemoryBudget(static_cast<double>(desc.film.width) * desc.film.height * 56.0,
                      (desc.path.empty() ? std::string("scene") : desc.path) + ": the film (" +
                          std::to_string(desc.film.width) + " x " +
                          std::to_string(desc.film.height) + ")");
    camera_ = Camera(desc.camera, desc.film.width, desc.film.height);
    width_ = desc.film.width;
    height_ = desc.film.height;
}

void Scene::createLights(const SceneDesc& desc) {
    std::vector<std::unique_ptr<Light>> lights;
    for (const auto& light : desc.lights) lights.push_back(light->create());
    if (lights.empty()) lights.push_back(std::make_unique<EnvironmentLight>(skyLight()));
    lights_ = std::move(lights);
    lightSamplerDesc_ = desc.lightSampler;
}

void Scene::setLights(const SceneDesc& desc) {
    createLights(desc);
    buildLightSampler();
}

void Scene::buildLightSampler() {
    switch (lightSamplerDesc_.kind) {
        case LightSamplerKind::Uniform:
            lightSampler_ = LightSampler(lights_.size());
            break;
        case LightSamplerKind::Weights:
            lightSampler_ = LightSampler(lightSamplerDesc_.weights);
            // Only light samples reach a point or directional light: weight 0 would drop it.
            for (size_t i = 0; i < lights_.size(); ++i)
                if (lights_[i]->isDelta() && lightSampler_.pmf(i) == 0)
                    throw InputError("light_sampler.weights[" + std::to_string(i) +
                                     "] = 0, but lights[" + std::to_string(i) +
                                     "] is a point or directional light, which only light "
                                     "samples reach: allowed > 0");
            break;
        case LightSamplerKind::Power: {
            // The geometry's bounding sphere (radius 1 for an empty scene).
            const double r = accel_->boundingRadius();
            std::vector<double> power;
            for (const auto& l : lights_) power.push_back(l->power(r > 0 ? r : 1.0).average());
            lightSampler_ = LightSampler(power);
            break;
        }
    }
}

std::vector<FramedCurve> yarnPlyCurves(const Curve& curve, const YarnDesc& yarn,
                                       const PlyParams* fibers, size_t curveIndex) {
    const double radius = largestRadius(curve, yarn);
    const double step = sampleStep(radius > 0 ? radius : 1.0, yarn.plies, yarn.plyTwist, fibers);
    const FramedCurve centre =
        frameCurve(curve, yarn.scale, yarn.radius, step, yarn.curves, curveIndex);
    return plyCurves(centre, yarn.plies, yarn.plyTwist);
}

uint64_t fiberSeed(size_t y, size_t c, size_t j, uint64_t arrangement) {
    const uint64_t seed = mixBits(mixBits(mixBits(y + 1) ^ (c + 1)) ^ (j + 1));
    return arrangement == 0 ? seed : mixBits(seed ^ mixBits(arrangement));
}

}  // namespace weft::render
