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
#include "weft/gather/gather_folder.h"

namespace weft {

namespace {

std::string inDir(const std::string& dir, const char* name) {
    return (std::filesystem::path(dir) / name).string();
}

}  // namespace

void addInt64Npy(const std::string& path, const std::vector<size_t>& shape,
                 std::vector<int64_t>& into) {
    const std::vector<int64_t> values = readGatherArray<int64_t>(
        path, "<i8", shape,
        {0, std::numeric_limits<double>::infinity(), " (counts and weights)"});
    for (size_t k = 0; k < into.size(); ++k) {
        if (into[k] > std::numeric_limits<int64_t>::max() - values[k])
            throw InputError(path + ": " + gatherElementName(k, shape) +
                             " overflows int64 when added to the other parts");
        into[k] += values[k];
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
    if (!s.sumExitOffset.empty())
        writeNpy(file("sum_exit_offset.npy"), s.sumExitOffset.data(), exitOffsetShape());
    if (!s.sumMExit.empty())
        writeNpy(file("sum_m_exit.npy"), s.sumMExit.data(), {ti, pi, to, po, 3});
    writeNpy(file("depth.npy"), s.depth.data(), {s.depth.size()});
    writePlyLines(file("ply.txt"), s.plyLines, s.fiberRadius);
    if (o.anyColour) writeColourPaths(out.path(), s.colourPaths);
    nlohmann::json meta = gatherInputs(o, s.fiberRadius, s.period, s.segments);
    meta.update({
        {"format", kGatherPartFormat},
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
          {"count_t",
           "int64 (TI,PI): this shard's T paths (no fiber interaction) per incident bin"},
          {"sum_r", "int64 (TI,PI,TO,PO,3): summed R path weights, in units of 2^-32"},
          {"sum_m", "int64 (TI,PI,TO,PO,3): summed M path weights, in units of 2^-32"},
          {"sum_m_exit",
           "int64 (TI,PI,TO,PO,3): sum_m with wo in the exit frame (gather.h), 2^-32 units"},
          {"sum_truncated",
           "int64 (TI,PI,3): summed weight of paths cut at max_depth, 2^-32 units"},
          {"sum_exit_distance",
           "int64 (" + std::to_string(kExitDistance) +
               ",3): summed M path weights by entry-to-exit distance (gather.h), 2^-32 units"},
          {"sum_exit_offset",
           "int64 (" + std::to_string(kExitOffsetTheta) + "," + std::to_string(kExitOffsetPhi) +
               "," + std::to_string(kExitOffsetSlots) +
               ",3): summed M path weights by signed exit offset per incident cell (gather.h), "
               "2^-32 units"},
          {"depth",
           "int64 (max_depth+2): paths by number of fiber interactions; last: truncated"}}},
    });
    if (o.anyColour) meta["arrays"].update(colourPathArrayDescriptions());
    writeFileAtomic(file("meta.json"), meta.dump(2) + "\n");
    out.commit();
}

MergedGather mergeGatherParts(const std::vector<std::string>& partDirs) {
    if (partDirs.empty()) throw InputError("no gather parts to merge");
    // Every meta.json first: a part that does not belong fails before any array is read.
    std::vector<GatherFolder> parts;
    for (const std::string& dir : partDirs)
        parts.push_back(readGatherFolder(dir, GatherFolderKind::Part));
    for (size_t k = 1; k < parts.size(); ++k)
        for (const std::string_view field : sharedPartFields()) {
            const nlohmann::json mine = jsonAtPath(parts[k].meta, field),
                                 first = jsonAtPath(parts[0].meta, field);
            if (mine != first)
                throw InputError(parts[k].metaPath + ": \"" + std::string(field) + "\" is " +
                                 (mine.is_null() ? "missing" : mine.dump()) + ", but " +
                                 parts[0].metaPath + " has " +
                                 (first.is_null() ? "none" : first.dump()) +
                                 ": the parts are not shards of one gather");
        }
    std::vector<Shard> shards;
    std::vector<std::string> names, files;
    for (const GatherFolder& p : parts) {
        shards.push_back(p.options.shard), names.push_back(p.dir);
        for (std::string& f : p.files()) files.push_back(std::move(f));
    }
    checkCompleteShardSet(shards, names);
    // A part's file linked to another's would be added twice.
    checkDistinctFiles(files);
    const int64_t n = shards[0].count;

    MergedGather m;
    m.options = parts[0].options;
    m.options.shard = Shard{};
    m.shards = n;
    m.sums = emptyGatherSums(m.options);
    GatherSums& sums = m.sums;
    // The merge writes the ply that the options give: every part was traced on it.
    for (const GatherFolder& p : parts) checkTracedPly(p, sums);
    const RdmBins& b = m.options.bins;
    const size_t ti = b.thetaI, pi = b.phiI, to = b.thetaO, po = b.phiO;
    // Shard order is path order: the recorded paths of an any-colour gather
    // are concatenated in it.
    std::sort(parts.begin(), parts.end(), [](const GatherFolder& a, const GatherFolder& b) {
        return a.options.shard.index < b.options.shard.index;
    });
    for (const GatherFolder& p : parts) {
        const auto file = [&](const char* name) { return p.file(name); };
        // The counts first, checked against the shard's paths and each other;
        // their sums over the parts are at most the gather's paths.
        const GatherCounts counts = readGatherCounts(p);
        for (size_t k = 0; k < counts.count.size(); ++k) {
            sums.count[k] += counts.count[k];
            sums.countT[k] += counts.countT[k];
        }
        for (size_t k = 0; k < counts.depth.size(); ++k) sums.depth[k] += counts.depth[k];
        addInt64Npy(file("sum_r.npy"), {ti, pi, to, po, 3}, sums.sumR);
        addInt64Npy(file("sum_m.npy"), {ti, pi, to, po, 3}, sums.sumM);
        addInt64Npy(file("sum_truncated.npy"), {ti, pi, 3}, sums.sumTruncated);
        addInt64Npy(file("sum_exit_distance.npy"), {kExitDistance, 3}, sums.sumExitDistance);
        // Parts written before the exit offsets were recorded have none: the
        // merge then has none either.
        const auto addOptional = [&](const char* name, const std::vector<size_t>& shape,
                                     std::vector<int64_t>& into) {
            std::error_code ec;
            if (into.empty()) return;
            if (std::filesystem::exists(file(name), ec))
                addInt64Npy(file(name), shape, into);
            else
                into.clear();
        };
        addOptional("sum_exit_offset.npy", exitOffsetShape(), sums.sumExitOffset);
        addOptional("sum_m_exit.npy", {ti, pi, to, po, 3}, sums.sumMExit);
        if (m.options.anyColour) {
            const std::vector<ColourPath> recorded = readColourPaths(p, counts);
            sums.colourPaths.insert(sums.colourPaths.end(), recorded.begin(), recorded.end());
        }
        // Checked by readGatherFolder.
        const nlohmann::json& meta = p.meta;
        sums.rays += meta.at("rays").get<int64_t>();
        sums.axialPaths += meta.at("axial_paths").get<int64_t>();
        sums.depthSum += meta.at("depth_sum").get<int64_t>();
        sums.seconds += meta.at("elapsed_seconds").get<double>();
        sums.walkSeconds += meta.at("walk_seconds").get<double>();
        sums.threads = std::max(sums.threads, meta.at("threads").get<int>());
    }
    sums.firstPath = 0;
    sums.endPath = m.options.paths;
    return m;
}

}  // namespace weft
