#include "weft/gather/colour_paths.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <numeric>
#include <unordered_map>

#include "weft/core/error.h"
#include "weft/core/json_file.h"
#include "weft/core/json_reader.h"
#include "weft/core/npy.h"
#include "weft/core/text_parse.h"
#include "weft/gather/gather_merge.h"

namespace weft {

namespace {

std::string inDir(const std::string& dir, const char* name) {
    return (std::filesystem::path(dir) / name).string();
}

NpyArray readShaped(const std::string& path, const char* descr, size_t columns) {
    NpyArray a = readNpy(path);
    const bool shapeOk =
        columns == 0 ? a.shape.size() == 1 : a.shape.size() == 2 && a.shape[1] == columns;
    if (a.descr != descr || !shapeOk)
        throw InputError(path + ": expected " + descr + " of shape " +
                         (columns == 0 ? "(N,)" : "(N, " + std::to_string(columns) + ")") +
                         ", got " + a.descr + " " + npyShapeString(a.shape));
    return a;
}

// A recorded float32 weight as short as it reads back ("3e+38", "nan").
std::string formatWeight(float w) {
    char text[32];
    const auto end = std::to_chars(text, text + sizeof text, w).ptr;
    return std::string(text, end);
}

template <typename T>
T element(const NpyArray& a, size_t k) {
    T v;
    std::memcpy(&v, a.bytes.data() + k * sizeof v, sizeof v);
    return v;
}

}  // namespace

FiberParams colourBlindFiber(const FiberParams& fiber) {
    FiberParams white = fiber;
    white.cTT = Rgb(1.0);
    return white;
}

nlohmann::json colourPathArrayDescriptions() {
    return {{"paths_bins",
             "int32 (N,3): per recorded path, incident bin, outgoing bin (-1: truncated), "
             "number of TT events k"},
            {"paths_kind", "uint8 (N): 0 R, 1 M, 2 truncated at max_depth"},
            {"paths_weight",
             "float32 (N,3): the path's weight W0 for C_TT = 1; for C_TT its weight is "
             "W0 C_TT^k per channel"}};
}

ColourPathColumns colourPathColumns(const std::vector<ColourPath>& paths) {
    const size_t n = paths.size();
    ColourPathColumns c;
    c.bins.resize(n * 3);
    c.kinds.resize(n);
    c.weights.resize(n * 3);
    for (size_t k = 0; k < n; ++k) {
        const ColourPath& p = paths[k];
        c.bins[3 * k + 0] = p.incidentBin;
        c.bins[3 * k + 1] = p.outgoingBin;
        c.bins[3 * k + 2] = p.ttEvents;
        c.kinds[k] = p.kind;
        for (int ch = 0; ch < 3; ++ch) c.weights[3 * k + ch] = p.weight[ch];
    }
    return c;
}

void writeColourPaths(const std::string& dir, const std::vector<ColourPath>& paths) {
    const size_t n = paths.size();
    const ColourPathColumns c = colourPathColumns(paths);
    writeNpy(inDir(dir, "paths_bins.npy"), c.bins.data(), {n, 3});
    writeNpy(inDir(dir, "paths_kind.npy"), c.kinds.data(), {n});
    writeNpy(inDir(dir, "paths_weight.npy"), c.weights.data(), {n, 3});
}

namespace {

// The fixed-point sums of every colour hold the records: a record adds
// toFixed(W0 C_TT^k) <= toFixed(W0) for C_TT in [0, 1] (fiber.validate), so
// where the sums of W0 fit in int64, those of any colour do. Per channel, the
// total over all records bounds every cell; only when it does not fit are the
// cells summed one by one, to name the record that overflows one.
void checkRecordSums(const std::vector<ColourPath>& paths, const RdmBins& bins,
                     const std::string& weightPath) {
    constexpr int64_t kMax = std::numeric_limits<int64_t>::max();
    unsigned __int128 total[3] = {0, 0, 0};
    for (const ColourPath& p : paths)
        for (int c = 0; c < 3; ++c)
            total[c] += static_cast<uint64_t>(GatherSums::toFixed(p.weight[c]));
    if (total[0] <= kMax && total[1] <= kMax && total[2] <= kMax) return;
    static const char* const kKind[] = {"R", "M", "truncated"};
    const size_t nOut = bins.outgoingCount();
    std::unordered_map<uint64_t, int64_t> cells;
    for (size_t k = 0; k < paths.size(); ++k) {
        const ColourPath& p = paths[k];
        const uint64_t cell = p.kind == ColourPath::Truncated
                                  ? static_cast<uint64_t>(p.incidentBin)
                                  : static_cast<uint64_t>(p.incidentBin) * nOut + p.outgoingBin;
        for (int c = 0; c < 3; ++c) {
            int64_t& sum = cells[(cell * 3 + c) * 3 + p.kind];
            if (__builtin_add_overflow(sum, GatherSums::toFixed(p.weight[c]), &sum))
                throw InputError(
                    weightPath + ": row " + std::to_string(k) + ": weight " +
                    formatWeight(p.weight[c]) + " in channel " + std::to_string(c) +
                    " takes the summed " + kKind[p.kind] + " weight of incident bin " +
                    std::to_string(p.incidentBin) +
                    (p.kind == ColourPath::Truncated
                         ? std::string()
                         : ", outgoing bin " + std::to_string(p.outgoingBin)) +
                    " beyond what the fixed-point sums hold (2^31 in 2^-32 units: "
                    "GatherSums, docs/limits.md)");
        }
    }
}

}  // namespace

std::vector<ColourPath> readColourPaths(const GatherFolder& f, const GatherCounts& counts) {
    const GatherOptions& o = f.options;
    const std::string binsPath = f.file("paths_bins.npy"), kindPath = f.file("paths_kind.npy"),
                      weightPath = f.file("paths_weight.npy");
    const NpyArray bins = readShaped(binsPath, "<i4", 3);
    const NpyArray kinds = readShaped(kindPath, "|u1", 0);
    const NpyArray weights = readShaped(weightPath, "<f4", 3);
    const size_t n = bins.shape[0];
    if (kinds.shape[0] != n || weights.shape[0] != n)
        throw InputError(f.dir + ": paths_bins.npy, paths_kind.npy and paths_weight.npy have " +
                         std::to_string(n) + ", " + std::to_string(kinds.shape[0]) + " and " +
                         std::to_string(weights.shape[0]) + " rows (must be equal)");
    // Records are kept for paths that met a fiber: at most count - count_t per incident bin.
    const int64_t interacting = std::accumulate(counts.count.begin(), counts.count.end(),
                                                int64_t{0}) -
                                std::accumulate(counts.countT.begin(), counts.countT.end(),
                                                int64_t{0});
    if (static_cast<int64_t>(n) > interacting)
        throw InputError(binsPath + ": " + std::to_string(n) +
                         " recorded paths, more than the " + std::to_string(interacting) +
                         " paths that met a fiber (count.npy - count_t.npy)");
    const int64_t nIn = static_cast<int64_t>(o.bins.incidentCount()),
                  nOut = static_cast<int64_t>(o.bins.outgoingCount());
    const auto bad = [](const std::string& path, size_t row, const std::string& what) {
        return InputError(path + ": row " + std::to_string(row) + ": " + what);
    };
    std::vector<int64_t> perBin(static_cast<size_t>(nIn), 0);
    std::vector<ColourPath> paths(n);
    for (size_t k = 0; k < n; ++k) {
        ColourPath& p = paths[k];
        p.incidentBin = element<int32_t>(bins, 3 * k);
        p.outgoingBin = element<int32_t>(bins, 3 * k + 1);
        p.ttEvents = element<int32_t>(bins, 3 * k + 2);
        const uint8_t kind = element<uint8_t>(kinds, k);
        if (kind > ColourPath::Truncated)
            throw bad(kindPath, k,
                      "kind " + std::to_string(kind) + " (allowed: 0 R, 1 M, 2 truncated)");
        p.kind = static_cast<ColourPath::Kind>(kind);
        if (p.incidentBin < 0 || p.incidentBin >= nIn)
            throw bad(binsPath, k,
                      "incident bin " + std::to_string(p.incidentBin) + " (allowed: 0.." +
                          std::to_string(nIn - 1) + ")");
        if (++perBin[p.incidentBin] > counts.interacting(p.incidentBin))
            throw bad(binsPath, k,
                      "incident bin " + std::to_string(p.incidentBin) + " has more records than " +
                          "its " + std::to_string(counts.interacting(p.incidentBin)) +
                          " paths that met a fiber (count.npy - count_t.npy)");
        if (p.kind == ColourPath::Truncated ? p.outgoingBin != -1
                                            : p.outgoingBin < 0 || p.outgoingBin >= nOut)
            throw bad(binsPath, k,
                      "outgoing bin " + std::to_string(p.outgoingBin) +
                          (p.kind == ColourPath::Truncated
                               ? " of a truncated path (must be -1)"
                               : " (allowed: 0.." + std::to_string(nOut - 1) + ")"));
        const int maxTT = p.kind == ColourPath::R ? 1 : o.maxDepth;
        if (p.ttEvents < 0 || p.ttEvents > maxTT)
            throw bad(binsPath, k,
                      "TT events " + std::to_string(p.ttEvents) + " (allowed: 0.." +
                          std::to_string(maxTT) +
                          (p.kind == ColourPath::R ? " for an R path)" : ", max_depth)"));
        for (int c = 0; c < 3; ++c) {
            p.weight[c] = element<float>(weights, 3 * k + c);
            // W0 2^32 must be an int64 (GatherSums::toFixed).
            if (!(p.weight[c] >= 0 && p.weight[c] < kMaxRecordWeight))
                throw bad(weightPath, k,
                          "weight " + formatWeight(p.weight[c]) + " in channel " +
                              std::to_string(c) +
                              " (allowed: finite, >= 0 and < 2^31: the fixed-point sums of a "
                              "gather add weights in units of 2^-32 as int64)");
        }
    }
    checkRecordSums(paths, o.bins, weightPath);
    return paths;
}

namespace {

// The any-colour gather `dir`, its meta.json, counts and ply checked.
GatherFolder readAnyColourGather(const std::string& dir) {
    GatherFolder f = readGatherFolder(dir, GatherFolderKind::Gather);
    if (!f.options.anyColour)
        throw InputError(f.metaPath +
                         ": not an any-colour gather (\"any_colour\" is false or missing): its "
                         "paths were not recorded; gather again with weft gather --any-colour");
    checkDistinctFiles(f.files());
    return f;
}

}  // namespace

std::vector<ColourPath> loadColourPaths(const std::string& dir, GatherOptions* options) {
    const GatherFolder f = readAnyColourGather(dir);
    if (options) *options = f.options;
    return readColourPaths(f, readGatherCounts(f));
}

RecolouredGather recolourGather(const std::string& dir, const Rgb& cTT) {
    const auto start = std::chrono::steady_clock::now();
    const GatherFolder f = readAnyColourGather(dir);
    GatherOptions o = f.options;
    const JsonObjectReader r(f.meta, f.metaPath);
    RecolouredGather result;
    result.gatheredCTT = o.fiber.cTT;
    GatherSums& sums = result.sums;
    sums = emptyGatherSums(o);
    // The recolouring writes the ply that the options give: the gather's must be it.
    checkTracedPly(f, sums);
    // The records do not keep where paths left the ply: no exit distances.
    sums.sumExitDistance.clear();
    sums.sumExitOffset.clear();
    sums.sumMExit.clear();
    const GatherCounts counts = readGatherCounts(f);
    sums.count = counts.count;
    sums.countT = counts.countT;
    sums.depth = counts.depth;
    const std::vector<ColourPath> paths = readColourPaths(f, counts);
    o.fiber.cTT = cTT;
    o.fiber.validate("--c-tt");
    for (const ColourPath& p : paths)
        addColourPath(sums, p, cTT, [](int64_t& cell, int64_t v) { cell += v; });

    // Statistics of the walks, as the gather recorded them.
    for (int d = 1; d <= o.maxDepth + 1; ++d)
        sums.depthSum += static_cast<int64_t>(std::min(d, o.maxDepth)) * sums.depth[d];
    sums.rays = r.integer("rays", {0, std::numeric_limits<int64_t>::max()});
    sums.axialPaths = std::llround(r.number("axial_fraction", NumberRange::closed(0, 1)) * o.paths);
    sums.walkSeconds = r.number("walk_seconds", NumberRange::atLeast(0));
    sums.threads = 1;
    sums.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    sums.firstPath = 0;
    sums.endPath = o.paths;
    o.anyColour = false;  // the result is an ordinary gather of one colour
    result.options = o;
    return result;
}

}  // namespace weft
