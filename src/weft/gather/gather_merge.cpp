#include "weft/gather/gather_merge.h"

#include <algorithm>
#include <climits>
#include <cstring>
#include <filesystem>
#include <limits>
#include <numeric>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/json_file.h"
#include "weft/core/json_reader.h"
#include "weft/core/npy.h"
#include "weft/gather/colour_paths.h"

namespace weft {

namespace {

constexpr const char* kPartFormat = "weft-gather-part";

std::string inDir(const std::string& dir, const char* name) {
    return (std::filesystem::path(dir) / name).string();
}

// One part's meta.json, read and checked on its own.
struct Part {
    std::string dir, metaPath;
    nlohmann::json meta;
    GatherOptions options;  // shard: this part's
};

Part readPart(const std::string& dir) {
    Part p;
    p.dir = dir;
    p.metaPath = inDir(dir, "meta.json");
    p.meta = readJsonFile(p.metaPath);
    const JsonObjectReader r(p.meta, p.metaPath);
    const std::string format = r.string("format");
    if (format == "weft-gather")
        throw InputError(p.metaPath +
                         ": a whole gather, not a shard of one (\"format\" is \"weft-gather\"): "
                         "merge the directories that weft gather --shard K/N wrote");
    if (format != kPartFormat)
        throw InputError(p.metaPath + ": not a gather shard (\"format\" is \"" + format +
                         "\", expected \"" + kPartFormat + "\")");
    r.integer("version", {1, 1, " (the part format this weft reads)"});
    GatherOptions& o = p.options;
    o = gatherOptionsFromJson(p.meta, p.metaPath);
    const JsonObjectReader shard = r.object("shard");
    o.shard.count = shard.integer("count", {1, Shard::kMaxCount});
    o.shard.index = shard.integer("index", {0, o.shard.count - 1});
    try {
        o.validate();
    } catch (const InputError& e) {
        throw InputError(p.metaPath + ": " + e.what());
    }
    const int64_t first = shard.integer("first_path", {0, kMaxPaths});
    const int64_t end = shard.integer("end_path", {0, kMaxPaths});
    if (first != o.shard.begin(o.paths) || end != o.shard.end(o.paths))
        throw InputError(p.metaPath + ": shard " + o.shard.toString() + " of " +
                         std::to_string(o.paths) + " paths covers [" +
                         std::to_string(o.shard.begin(o.paths)) + ", " +
                         std::to_string(o.shard.end(o.paths)) + "), but \"shard\" says [" +
                         std::to_string(first) + ", " + std::to_string(end) + ")");
    return p;
}

// What the shards of one gather share, field by field (JSON paths in meta.json).
std::vector<std::pair<std::string, nlohmann::json>> sharedFields(const Part& p) {
    const nlohmann::json& m = p.meta;
    return {{"material", m.at("material")},
            {"fiber", m.at("fiber")},
            {"ply.fibers", m.at("ply").at("fibers")},
            {"ply.density", m.at("ply").at("density")},
            {"ply.twist", m.at("ply").at("twist")},
            {"ply.segments_per_twist", m.at("ply").at("segments_per_twist")},
            {"bins", m.at("bins")},
            {"paths", m.at("paths")},
            {"seed", m.at("seed")},
            {"ply_seed", m.at("ply_seed")},
            {"max_depth", m.at("max_depth")},
            {"any_colour", m.value("any_colour", nlohmann::json(false))},
            {"shard.count", m.at("shard").at("count")},
            {"versions.weft", m.contains("versions") && m.at("versions").is_object() &&
                                      m.at("versions").contains("weft")
                                  ? m.at("versions").at("weft")
                                  : nlohmann::json()}};
}

}  // namespace

void addInt64Npy(const std::string& path, const std::vector<size_t>& shape,
                 std::vector<int64_t>& into) {
    const NpyArray a = readNpy(path);
    if (a.descr != "<i8" || a.shape != shape)
        throw InputError(path + ": expected <i8 of shape " + npyShapeString(shape) + ", got " +
                         a.descr + " " + npyShapeString(a.shape));
    for (size_t k = 0; k < into.size(); ++k) {
        int64_t v;
        std::memcpy(&v, a.bytes.data() + k * sizeof v, sizeof v);
        if (v < 0)
            throw InputError(path + ": element " + std::to_string(k) + " is " +
                             std::to_string(v) + " (must be >= 0)");
        if (into[k] > std::numeric_limits<int64_t>::max() - v)
            throw InputError(path + ": element " + std::to_string(k) +
                             " overflows int64 when added to the other parts");
        into[k] += v;
    }
}

// Rows of sum_exit_distance.npy.
constexpr size_t kExitDistance = static_cast<size_t>(kExitDistanceBins) + 1;

void writeGatherPart(const GatherSums& s, const GatherOptions& o, TempDirCommit& out) {
    const auto file = [&](const char* name) { return inDir(out.path(), name); };
    const RdmBins& b = s.bins;
    const size_t ti = b.thetaI, pi = b.phiI, to = b.thetaO, po = b.phiO;
    writeNpy(file("count.npy"), s.count.data(), {ti, pi});
    writeNpy(file("count_t.npy"), s.countT.data(), {ti, pi});
    writeNpy(file("sum_r.npy"), s.sumR.data(), {ti, pi, to, po, 3});
    writeNpy(file("sum_m.npy"), s.sumM.data(), {ti, pi, to, po, 3});
    writeNpy(file("sum_truncated.npy"), s.sumTruncated.data(), {ti, pi, 3});
    writeNpy(file("sum_exit_distance.npy"), s.sumExitDistance.data(), {kExitDistance, 3});
    writeNpy(file("depth.npy"), s.depth.data(), {s.depth.size()});
    writePlyLines(file("ply.txt"), s.plyLines, s.fiberRadius);
    if (o.anyColour) writeColourPaths(out.path(), s.colourPaths);
    nlohmann::json meta = gatherInputs(o, s.fiberRadius, s.period, s.segments);
    meta.update({
        {"format", kPartFormat},
        {"version", 1},
        {"shard",
         {{"index", o.shard.index},
          {"count", o.shard.count},
          {"first_path", s.firstPath},
          {"end_path", s.endPath}}},
        {"rays", s.rays},
        {"axial_paths", s.axialPaths},
        {"depth_sum", s.depthSum},
        {"elapsed_seconds", s.seconds},
        {"walk_seconds", s.walkSeconds},
        {"threads", s.threads},
        {"arrays",
         {{"count", "int64 (TI,PI): this shard's paths per incident bin"},
          {"count_t", "int64 (TI,PI): this shard's T paths (no fiber interaction) per incident bin"},
          {"sum_r", "int64 (TI,PI,TO,PO,3): summed R path weights, in units of 2^-32"},
          {"sum_m", "int64 (TI,PI,TO,PO,3): summed M path weights, in units of 2^-32"},
          {"sum_truncated", "int64 (TI,PI,3): summed weight of paths cut at max_depth, 2^-32 units"},
          {"sum_exit_distance",
           "int64 (" + std::to_string(kExitDistance) +
               ",3): summed M path weights by entry-to-exit distance (gather.h), 2^-32 units"},
          {"depth", "int64 (max_depth+2): paths by number of fiber interactions; last: truncated"}}},
    });
    if (o.anyColour) meta["arrays"].update(colourPathArrayDescriptions());
    writeFileAtomic(file("meta.json"), meta.dump(2) + "\n");
    out.commit();
}

MergedGather mergeGatherParts(const std::vector<std::string>& partDirs) {
    if (partDirs.empty()) throw InputError("no gather parts to merge");
    // Every meta.json first: a part that does not belong fails before any array is read.
    std::vector<Part> parts;
    for (const std::string& dir : partDirs) parts.push_back(readPart(dir));
    const auto first = sharedFields(parts[0]);
    for (size_t k = 1; k < parts.size(); ++k) {
        const auto fields = sharedFields(parts[k]);
        for (size_t f = 0; f < fields.size(); ++f)
            if (fields[f].second != first[f].second)
                throw InputError(parts[k].metaPath + ": \"" + fields[f].first + "\" is " +
                                 fields[f].second.dump() + ", but " + parts[0].metaPath +
                                 " has " + first[f].second.dump() +
                                 ": the parts are not shards of one gather");
    }
    std::vector<Shard> shards;
    std::vector<std::string> names;
    for (const Part& p : parts) shards.push_back(p.options.shard), names.push_back(p.dir);
    checkCompleteShardSet(shards, names);
    const int64_t n = shards[0].count;

    MergedGather m;
    m.options = parts[0].options;
    m.options.shard = Shard{};
    m.shards = n;
    m.sums = emptyGatherSums(m.options);
    GatherSums& sums = m.sums;
    const RdmBins& b = m.options.bins;
    const size_t ti = b.thetaI, pi = b.phiI, to = b.thetaO, po = b.phiO;
    const size_t depthSize = sums.depth.size();
    // Shard order is path order: the recorded paths of an any-colour gather
    // are concatenated in it.
    std::sort(parts.begin(), parts.end(), [](const Part& a, const Part& b) {
        return a.options.shard.index < b.options.shard.index;
    });
    for (const Part& p : parts) {
        const auto file = [&](const char* name) { return inDir(p.dir, name); };
        const Shard& shard = p.options.shard;
        const int64_t paths = shard.end(m.options.paths) - shard.begin(m.options.paths);
        // The counts first, checked against the shard's paths.
        std::vector<int64_t> count(sums.count.size(), 0), depth(depthSize, 0);
        addInt64Npy(file("count.npy"), {ti, pi}, count);
        addInt64Npy(file("depth.npy"), {depthSize}, depth);
        const int64_t countSum = std::accumulate(count.begin(), count.end(), int64_t{0});
        const int64_t depthSum = std::accumulate(depth.begin(), depth.end(), int64_t{0});
        if (countSum != paths || depthSum != paths)
            throw InputError(p.dir + ": count.npy and depth.npy must each sum to the shard's " +
                             std::to_string(paths) + " paths, got " + std::to_string(countSum) +
                             " and " + std::to_string(depthSum));
        for (size_t k = 0; k < count.size(); ++k) sums.count[k] += count[k];
        for (size_t k = 0; k < depthSize; ++k) sums.depth[k] += depth[k];
        addInt64Npy(file("count_t.npy"), {ti, pi}, sums.countT);
        addInt64Npy(file("sum_r.npy"), {ti, pi, to, po, 3}, sums.sumR);
        addInt64Npy(file("sum_m.npy"), {ti, pi, to, po, 3}, sums.sumM);
        addInt64Npy(file("sum_truncated.npy"), {ti, pi, 3}, sums.sumTruncated);
        addInt64Npy(file("sum_exit_distance.npy"), {kExitDistance, 3}, sums.sumExitDistance);
        if (m.options.anyColour) {
            const std::vector<ColourPath> recorded = readColourPaths(p.dir, m.options, paths);
            sums.colourPaths.insert(sums.colourPaths.end(), recorded.begin(), recorded.end());
        }
        const JsonObjectReader r(p.meta, p.metaPath);
        sums.rays += r.integer("rays", {0, std::numeric_limits<int64_t>::max() / 65536});
        sums.axialPaths += r.integer("axial_paths", {0, paths});
        sums.depthSum += r.integer("depth_sum", {0, paths * 1000000});
        sums.seconds += r.number("elapsed_seconds", NumberRange::atLeast(0));
        sums.walkSeconds += r.number("walk_seconds", NumberRange::atLeast(0));
        sums.threads = std::max(sums.threads, static_cast<int>(r.integer("threads", {1, 1024})));
    }
    for (size_t k = 0; k < sums.count.size(); ++k)
        if (sums.countT[k] > sums.count[k])
            throw InputError("count_t.npy: incident bin " + std::to_string(k) + " has " +
                             std::to_string(sums.countT[k]) + " T paths of " +
                             std::to_string(sums.count[k]) + " in the merged parts");
    sums.firstPath = 0;
    sums.endPath = m.options.paths;
    return m;
}

}  // namespace weft
