// A family gather (family.h): the box, its points and the gathers of the points.
#include "weft/gather/family.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/json_file.h"
#include "weft/core/json_message.h"
#include "weft/core/json_reader.h"
#include "weft/core/progress.h"
#include "weft/core/rng.h"

namespace weft {

namespace {

namespace fs = std::filesystem;

constexpr const char* kFamilyFormat = "weft family gather";
constexpr int kFamilyVersion = 1;

std::string pointSource(int k) { return "family point " + std::to_string(k); }

// Whether a gather folder's recorded inputs (gatherOptionsFromJson) are `want`'s.
bool sameGatherInputs(const GatherOptions& have, const GatherOptions& want) {
    return have.fiber.toJson() == want.fiber.toJson() && have.ply.fibers == want.ply.fibers &&
           have.ply.density == want.ply.density && have.ply.twist == want.ply.twist &&
           have.paths == want.paths && have.seed == want.seed &&
           have.placementSeed() == want.placementSeed() &&
           have.bins.toString() == want.bins.toString() && have.maxDepth == want.maxDepth &&
           have.anyColour == want.anyColour &&
           (want.ply.twist == 0 || have.segmentsPerTwist == want.segmentsPerTwist);
}

// Point k's folder under `dir`: none, holding point k's gather (true), or
// InputError naming it when it holds another.
bool holdsPoint(const std::string& folder, const GatherOptions& want) {
    if (!fs::exists(folder)) return false;
    const std::string meta = folder + "/meta.json";
    const GatherOptions have = gatherOptionsFromJson(readJsonFile(meta), meta);
    if (!sameGatherInputs(have, want))
        throw InputError(folder +
                         " holds another gather than this family's point (its meta.json "
                         "differs in the fiber, ply, paths, seed or bins): remove it, or give "
                         "the options it was gathered with");
    return true;
}

}  // namespace

void validateFamilyBox(const FamilyBox& box, const std::string& source) {
    box.validate(source);
    // Both corners must be a ply and a fiber (every point between then is).
    for (const bool high : {false, true}) {
        const auto pick = [&](const ParameterRange& r) { return high ? r.hi : r.lo; };
        try {
            if (pick(box.fibers) > kMaxPlyFibers)
                throw InputError("ply: fibers (N) must be at most " +
                                 std::to_string(kMaxPlyFibers));
            PlyParams{static_cast<int>(pick(box.fibers)), pick(box.density), pick(box.twist)}
                .validate();
            const double c = pick(box.cR);
            FiberParams{Rgb(c, c, c), Rgb(0.5, 0.5, 0.5), pick(box.betaRDeg), pick(box.betaTTDeg),
                        pick(box.gammaTTDeg)}
                .validate("the box's " + std::string(high ? "upper" : "lower") + " corner");
        } catch (const InputError& e) {
            throw InputError(source + ": " + e.what());
        }
    }
}

void FamilyGatherOptions::validate() const {
    validateFamilyBox(box, "box");
    if (points < 1 || points > kMaxFamilyPoints)
        throw InputError("--points must be in [1, " + std::to_string(kMaxFamilyPoints) + "], got " +
                         std::to_string(points));
    if (pathsPerPoint < 1 || pathsPerPoint > kMaxPaths)
        throw InputError("--paths must be in [1, " + std::to_string(kMaxPaths) + "], got " +
                         std::to_string(pathsPerPoint));
    shard.validate(points, "--shard", "points");
    // The rest as any gather checks it, on the box's lower corner.
    GatherOptions corner = pointOptions(0, box.at({}));
    corner.validate();
}

GatherOptions FamilyGatherOptions::pointOptions(int k, const YarnPoint& p) const {
    GatherOptions o;
    o.fiber = fiberOf(p, Rgb(0.5, 0.5, 0.5));
    o.ply = plyOf(p);
    o.material = pointSource(k);
    o.paths = pathsPerPoint;
    o.seed = mixBits(seed + 0x9e3779b97f4a7c15ULL * (static_cast<uint64_t>(k) + 1));
    o.bins = bins;
    o.maxDepth = maxDepth;
    o.threads = threads;
    o.segmentsPerTwist = segmentsPerTwist;
    o.quiet = true;
    o.anyColour = true;
    return o;
}

std::string FamilyGatherOptions::pointFolder(int k) {
    char name[32];
    std::snprintf(name, sizeof name, "points/%05d", k);
    return name;
}

nlohmann::json familyMetadata(const FamilyGatherOptions& o, const std::vector<YarnPoint>& points) {
    nlohmann::json yarns = nlohmann::json::array();
    for (int k = 0; k < static_cast<int>(points.size()); ++k) {
        nlohmann::json y = points[k].toJson();
        y["folder"] = FamilyGatherOptions::pointFolder(k);
        y["seed"] = o.pointOptions(k, points[k]).seed;
        yarns.push_back(std::move(y));
    }
    nlohmann::json meta = {{"format", kFamilyFormat},
                           {"version", kFamilyVersion},
                           {"box", o.box.toJson()},
                           {"points", o.points},
                           {"paths_per_point", o.pathsPerPoint},
                           {"seed", o.seed},
                           {"bins", {o.bins.thetaI, o.bins.phiI, o.bins.thetaO, o.bins.phiO}},
                           {"max_depth", o.maxDepth},
                           {"segments_per_twist", o.segmentsPerTwist},
                           {"yarns", std::move(yarns)}};
    if (o.design != FamilyDesign::Halton) meta["design"] = familyDesignName(o.design);
    return meta;
}

FamilyGatherSummary gatherFamily(const FamilyGatherOptions& options, const std::string& dir) {
    options.validate();
    const std::vector<YarnPoint> points =
        familyPoints(options.box, options.points, options.seed, options.design);
    const std::string metaPath = dir + "/family.json";
    const std::string meta = familyMetadata(options, points).dump(1) + "\n";
    std::error_code ec;
    // A folder of something else is not taken over.
    if (fs::exists(dir) && !fs::is_empty(dir, ec) && !fs::exists(metaPath))
        throw InputError(dir +
                         " exists and is not a family folder (no family.json): give a new "
                         "or empty folder");
    fs::create_directories(fs::path(dir) / "points", ec);
    if (ec) throw InputError(dir + ": cannot create the family folder: " + ec.message());
    // Every shard writes the same text; another family's is refused.
    if (fs::exists(metaPath) && readFile(metaPath) != meta)
        throw InputError(metaPath +
                         " describes another family (other box, points, paths, seed "
                         "or bins): use another folder, or the options it was gathered with");
    writeFileAtomic(metaPath, meta);

    FamilyGatherSummary summary;
    const auto start = std::chrono::steady_clock::now();
    const int first = static_cast<int>(options.shard.begin(options.points));
    const int end = static_cast<int>(options.shard.end(options.points));
    Progress progress("gather family", static_cast<uint64_t>(end - first), options.quiet);
    for (int k = first; k < end; ++k) {
        const GatherOptions o = options.pointOptions(k, points[k]);
        const std::string folder = dir + "/" + FamilyGatherOptions::pointFolder(k);
        if (holdsPoint(folder, o)) {
            ++summary.pointsKept;
        } else {
            TempDirCommit out(folder);
            writeGather(gatherRdm(o), o, out, {{"family", {{"point", k}}}}, GatherFiles::Records);
            ++summary.pointsGathered;
            summary.paths += o.paths;
        }
        progress.add(1);
    }
    progress.finish();
    summary.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return summary;
}

nlohmann::json familyGatherSummaryJson(const FamilyGatherOptions& o, const FamilyGatherSummary& s,
                                       const std::string& dir) {
    return {{"out", dir},
            {"points", o.points},
            {"shard", o.shard.toString()},
            {"first_point", o.shard.begin(o.points)},
            {"end_point", o.shard.end(o.points)},
            {"points_gathered", s.pointsGathered},
            {"points_kept", s.pointsKept},
            {"paths", s.paths},
            {"seconds", s.seconds}};
}

std::string FamilyGather::pointDir(int k) const {
    return dir + "/" + FamilyGatherOptions::pointFolder(k);
}

FamilyGather loadFamilyGather(const std::string& dir) {
    const std::string metaPath = dir + "/family.json";
    const nlohmann::json meta = readJsonFile(metaPath);
    JsonObjectReader r(meta, metaPath);
    r.allowKeys({"format", "version", "box", "points", "paths_per_point", "seed", "design", "bins",
                 "max_depth", "segments_per_twist", "yarns"});
    if (r.string("format") != kFamilyFormat)
        throw InputError(metaPath + ": format is not \"" + std::string(kFamilyFormat) + "\"");
    r.integer("version", {kFamilyVersion, kFamilyVersion});
    FamilyGather family;
    family.dir = dir;
    FamilyGatherOptions& o = family.options;
    o.box = FamilyBox::fromJson(r.value("box"), metaPath + ": box");
    o.points = static_cast<int>(r.integer("points", {1, kMaxFamilyPoints}));
    o.pathsPerPoint = r.integer("paths_per_point", {1, kMaxPaths});
    o.seed = r.unsignedInteger("seed");
    if (r.has("design")) o.design = parseFamilyDesign(r.string("design"), metaPath + ": design");
    const std::vector<int64_t> bins = r.integers("bins", 4, 4, {1, 4096}, "(TI, PI, TO, PO)");
    o.bins = {static_cast<int>(bins[0]), static_cast<int>(bins[1]), static_cast<int>(bins[2]),
              static_cast<int>(bins[3])};
    o.maxDepth = static_cast<int>(r.integer("max_depth", {1, 1000000}));
    o.segmentsPerTwist = static_cast<int>(r.integer("segments_per_twist", {1, 1 << 20}));
    o.quiet = true;
    try {
        o.validate();
    } catch (const InputError& e) {
        throw InputError(metaPath + ": " + e.what());
    }
    // The yarns follow from the box and the seed: a file whose list was edited is refused.
    family.points = familyPoints(o.box, o.points, o.seed, o.design);
    const nlohmann::json& yarns = r.value("yarns");
    if (!yarns.is_array() || yarns.size() != static_cast<size_t>(o.points))
        throw InputError(metaPath + ": yarns: expected " + std::to_string(o.points) + " entries");
    std::vector<int> missing;
    for (int k = 0; k < o.points; ++k) {
        const std::string path = jsonIndexPath("yarns", static_cast<size_t>(k));
        if (YarnPoint::fromJson(yarns[k], metaPath, path, {"folder", "seed"}) != family.points[k])
            throw InputError(metaPath + ": " + path +
                             " is not the box's point for this seed (the file was edited)");
        if (!holdsPoint(family.pointDir(k), o.pointOptions(k, family.points[k])))
            missing.push_back(k);
    }
    if (!missing.empty()) {
        std::string list;
        for (size_t i = 0; i < missing.size() && i < 10; ++i)
            list += (i ? ", " : "") + std::to_string(missing[i]);
        if (missing.size() > 10) list += ", ...";
        throw InputError(dir + ": " + std::to_string(missing.size()) + " of " +
                         std::to_string(o.points) + " points not gathered yet (" + list +
                         "): run weft gather family again with the same options (and each "
                         "--shard K/N that holds them)");
    }
    return family;
}

}  // namespace weft
