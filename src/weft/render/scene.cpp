#include "weft/render/scene.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "weft/core/error.h"
#include "weft/core/json_message.h"
#include "weft/core/limits.h"
#include "weft/core/math.h"
#include "weft/core/progress.h"
#include "weft/core/rng.h"
#include "weft/fiber/fiber_bcsdf.h"
#include "weft/render/curves.h"
#include "weft/render/yarn_geometry.h"
#include "weft/yarn/dual_scattering.h"
#include "weft/yarn/yarn_model.h"

namespace weft::render {

const char* renderModeName(RenderMode mode) {
    switch (mode) {
        case RenderMode::Neural:
            return "neural";
        case RenderMode::Fiber:
            return "fiber";
        case RenderMode::Dual:
            return "dual";
    }
    return "unknown";
}

RenderMode parseRenderMode(const std::string& name, const std::string& field) {
    if (name == "neural") return RenderMode::Neural;
    if (name == "fiber") return RenderMode::Fiber;
    if (name == "dual") return RenderMode::Dual;
    throw InputError(field + " \"" + name + "\" is not a render mode: allowed neural, fiber, dual");
}

namespace {

std::unique_ptr<Light> makeLight(const LightDesc& desc) {
    switch (desc.type) {
        case LightDesc::Type::Sky:
            return std::make_unique<EnvironmentLight>(skyLight(desc.scale));
        case LightDesc::Type::Envmap:
            return std::make_unique<EnvironmentLight>(
                EnvironmentLight::load(desc.file, desc.scale, desc.rotateDeg));
        case LightDesc::Type::Sphere:
            return std::make_unique<SphereLight>(desc.center, desc.radius, desc.radiance);
        case LightDesc::Type::Constant:
            return std::make_unique<ConstantLight>(desc.radiance);
    }
    throw std::logic_error("unknown light type");
}

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

std::string geometryName(const SceneDesc& desc, size_t yarn, RenderMode mode) {
    return (desc.path.empty() ? std::string("scene") : desc.path) + ": yarns[" +
           std::to_string(yarn) + "] (" + desc.yarns[yarn].curves + "): the " +
           renderModeName(mode) + " geometry up to this yarn";
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

[[noreturn]] void tooMuchGeometry(const SceneDesc& desc, size_t yarn, RenderMode mode) {
    throw InputError((desc.path.empty() ? std::string("scene") : desc.path) + ": yarns[" +
                     std::to_string(yarn) + "] (" + desc.yarns[yarn].curves + "): the " +
                     renderModeName(mode) + " geometry would exceed " +
                     std::to_string(kMaxSceneSegments) +
                     " curve segments (about 60 bytes each in Embree); use fewer or shorter "
                     "curves, or a larger radius");
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

// The materials of a scene: one BSDF per distinct model file and colour,
// built the first time a yarn asks for it (a vertex-coloured yarn asks for
// each of its colours, yarn_geometry.h kColourSteps).
class SceneMaterials {
  public:
    SceneMaterials(const SceneDesc& desc, RenderMode mode, const YarnBsdfOptions& options,
                   std::vector<std::unique_ptr<Bsdf>>* bsdfs)
        : desc_(desc), mode_(mode), options_(options), bsdfs_(bsdfs) {}

    // The model of yarn entry y as its file holds it (each file loaded once).
    const YarnModel& model(size_t y) {
        const std::string& path = desc_.yarns[y].model;
        auto it = models_.find(path);
        if (it == models_.end()) it = models_.emplace(path, loadYarnModel(path)).first;
        return it->second;
    }

    // The material of yarn entry y in `colour` (none: the model's own).
    int material(size_t y, const std::optional<Rgb>& colour) {
        const YarnDesc& yarn = desc_.yarns[y];
        if (colour && last_ && last_->y == y && last_->colour == *colour) return last_->material;
        const std::vector<double> colourKey =
            colour ? std::vector<double>{colour->r, colour->g, colour->b} : std::vector<double>{};
        auto [it, inserted] = index_.try_emplace({yarn.model, colourKey}, 0);
        if (inserted) {
            if (bsdfs_->size() >= static_cast<size_t>(kMaxSceneMaterials))
                throw InputError(entryName(y) + ": more than " + std::to_string(kMaxSceneMaterials) +
                                 " materials (distinct models and colours) in the scene; give "
                                 "fewer distinct colours");
            it->second = static_cast<int>(bsdfs_->size());
            YarnModel m = model(y);
            if (colour) {
                const std::string what =
                    entryName(y) + (yarn.vertexColours.empty() ? ".colour" : ".vertex_colours");
                // Neural mode: the conditioned model of that colour; fiber and
                // dual mode: the fiber itself, whatever the model.
                if (mode_ == RenderMode::Neural) m = m.forColour(*colour, what);
                else m.fiber.cTT = *colour;
            }
            if (mode_ == RenderMode::Neural)
                bsdfs_->push_back(std::make_unique<YarnBsdf>(m, yarn.model, options_));
            else if (mode_ == RenderMode::Dual)
                bsdfs_->push_back(std::make_unique<DualScatteringBsdf>(m.fiber, m.ply));
            else
                bsdfs_->push_back(std::make_unique<FiberBcsdf>(m.fiber));
        }
        if (colour) last_ = Last{y, *colour, it->second};
        return it->second;
    }

  private:
    std::string entryName(size_t y) const {
        return (desc_.path.empty() ? std::string("scene") : desc_.path) + ": yarns[" +
               std::to_string(y) + "]";
    }

    const SceneDesc& desc_;
    RenderMode mode_;
    YarnBsdfOptions options_;
    std::vector<std::unique_ptr<Bsdf>>* bsdfs_;
    std::map<std::string, YarnModel> models_;
    std::map<std::pair<std::string, std::vector<double>>, int> index_;
    // The last coloured lookup: neighbouring segments mostly share a colour.
    struct Last {
        size_t y;
        Rgb colour;
        int material;
    };
    std::optional<Last> last_;
};

}  // namespace

std::vector<YarnEntryOverlap> checkYarnOverlap(const SceneDesc& desc,
                                               const std::vector<CurveSet>& curveSets) {
    std::vector<YarnCurves> yarns;
    for (size_t y = 0; y < desc.yarns.size(); ++y) {
        const std::optional<double> radius = overlapRadius(desc.yarns[y], curveSets[y]);
        if (!radius) return {};
        yarns.push_back({&curveSets[y], desc.yarns[y].scale, *radius});
    }
    const std::vector<YarnOverlap> overlaps = yarnOverlaps(yarns);
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

Scene::Scene(const SceneDesc& desc, RenderMode mode, bool quiet, const YarnBsdfOptions& yarnOptions)
    : mode_(mode),
      camera_(desc.camera, desc.film.width, desc.film.height),
      width_(desc.film.width),
      height_(desc.film.height),
      accel_(std::make_unique<TubeAccel>()) {
    const auto start = std::chrono::steady_clock::now();
    // The film: double RGB sums while rendering, then the float image and its
    // EXR and PNG encodings: about 56 bytes per pixel.
    checkMemoryBudget(static_cast<double>(width_) * height_ * 56.0,
                      (desc.path.empty() ? std::string("scene") : desc.path) + ": the film (" +
                          std::to_string(width_) + " x " + std::to_string(height_) + ")");
    for (const LightDesc& light : desc.lights) lights_.push_back(makeLight(light));
    if (lights_.empty()) lights_.push_back(std::make_unique<EnvironmentLight>(skyLight()));

    // One material per distinct model file and colour (SceneMaterials).
    SceneMaterials materials(desc, mode, yarnOptions, &bsdfs_);
    std::vector<CurveSet> curveSets;
    std::vector<int> entryMaterial(desc.yarns.size(), -1);  // -1: vertex-coloured
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
        if (yarn.vertexColours.empty()) entryMaterial[y] = materials.material(y, yarn.colour);
        else if (!read.empty()) materials.material(y, read.front().colours.front());
    }
    // Before the geometry: what the render will draw inside other yarns.
    stats_.yarnOverlap = checkYarnOverlap(desc, curveSets);

    Progress progress("build " + std::string(renderModeName(mode)) + " geometry",
                      static_cast<uint64_t>(stats_.curves), quiet);
    int64_t planned = 0;
    for (size_t y = 0; y < desc.yarns.size(); ++y) {
        const YarnDesc& yarn = desc.yarns[y];
        const bool vertexColoured = !yarn.vertexColours.empty();
        const int material = entryMaterial[y];
        const PlyParams& fibers = materials.model(y).ply;
        const std::vector<Curve>& curves = curveSets[y].curves;
        for (size_t c = 0; c < curves.size(); ++c) {
            const double radius = largestRadius(curves[c], yarn);
            const double step = sampleStep(radius > 0 ? radius : 1.0, yarn.plies, yarn.plyTwist,
                                           mode == RenderMode::Fiber ? &fibers : nullptr);
            // The control polygon's length bounds the samples frameCurve will
            // make (to within the spline's bulge): refuse before allocating them.
            double chord = 0;
            const std::vector<Vec3>& cp = curves[c].points;
            for (size_t k = 0; k + 1 < cp.size(); ++k) chord += length(cp[k + 1] - cp[k]);
            if (curves[c].closed && cp.size() > 1) chord += length(cp.front() - cp.back());
            const double estimate = (chord * yarn.scale / step + 1) * yarn.plies *
                                    (drawsPlies(mode) ? 1 : fibers.fibers);
            if (static_cast<double>(planned) + estimate > static_cast<double>(kMaxSceneSegments))
                tooMuchGeometry(desc, y, mode);
            checkMemoryBudget((static_cast<double>(planned) + estimate) * kBytesPerSegment,
                              geometryName(desc, y, mode));
            const FramedCurve centre =
                frameCurve(curves[c], yarn.scale, yarn.radius, step, yarn.curves, c);
            const std::vector<FramedCurve> plies = plyCurves(centre, yarn.plies, yarn.plyTwist);
            for (size_t j = 0; j < plies.size(); ++j) {
                // Refuse before allocating: a fiber-mode scene costs fibers x samples segments.
                const int64_t tubes = drawsPlies(mode) ? 1 : fibers.fibers;
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
                if (drawsPlies(mode)) {
                    accel_->addGeometry({toTube(plies[j])}, first, std::move(along));
                } else {
                    // Seeded by where the ply is, not by the render seed.
                    const uint64_t seed = mixBits(mixBits(mixBits(y + 1) ^ (c + 1)) ^ (j + 1));
                    accel_->addGeometry(fiberTubes(plies[j], fibers, seed), first,
                                        std::move(along));
                }
            }
            progress.add();
        }
    }
    accel_->commit();
    progress.finish();
    stats_.tubes = accel_->tubeCount();
    stats_.segments = accel_->segmentCount();
    stats_.embreeBytes = accel_->embreeBytes();
    stats_.embreePeakBytes = accel_->embreePeakBytes();
    stats_.materials = static_cast<int64_t>(bsdfs_.size());
    for (const auto& bsdf : bsdfs_)
        stats_.materialBytes += static_cast<int64_t>(bsdf->memoryBytes());
    stats_.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace weft::render
