#include "weft/gather/colour_paths.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <numeric>

#include "weft/core/error.h"
#include "weft/core/json_file.h"
#include "weft/core/json_reader.h"
#include "weft/core/npy.h"
#include "weft/core/text_parse.h"
#include "weft/gather/gather_merge.h"
#include "weft/gather/rdm_io.h"

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

std::vector<ColourPath> readColourPaths(const std::string& dir, const GatherOptions& o,
                                        int64_t maxRows) {
    const std::string binsPath = inDir(dir, "paths_bins.npy"),
                      kindPath = inDir(dir, "paths_kind.npy"),
                      weightPath = inDir(dir, "paths_weight.npy");
    const NpyArray bins = readShaped(binsPath, "<i4", 3);
    const NpyArray kinds = readShaped(kindPath, "|u1", 0);
    const NpyArray weights = readShaped(weightPath, "<f4", 3);
    const size_t n = bins.shape[0];
    if (kinds.shape[0] != n || weights.shape[0] != n)
        throw InputError(dir + ": paths_bins.npy, paths_kind.npy and paths_weight.npy have " +
                         std::to_string(n) + ", " + std::to_string(kinds.shape[0]) + " and " +
                         std::to_string(weights.shape[0]) + " rows (must be equal)");
    if (static_cast<int64_t>(n) > maxRows)
        throw InputError(binsPath + ": " + std::to_string(n) + " recorded paths, more than the " +
                         std::to_string(maxRows) + " paths walked");
    const int64_t nIn = static_cast<int64_t>(o.bins.incidentCount()),
                  nOut = static_cast<int64_t>(o.bins.outgoingCount());
    const auto bad = [](const std::string& path, size_t row, const std::string& what) {
        return InputError(path + ": row " + std::to_string(row) + ": " + what);
    };
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
            if (!std::isfinite(p.weight[c]) || p.weight[c] < 0)
                throw bad(weightPath, k,
                          "weight " + std::to_string(p.weight[c]) + " (must be finite and >= 0)");
        }
    }
    return paths;
}

namespace {

// The options of the any-colour gather `dir` from its meta.json.
GatherOptions anyColourGatherOptions(const std::string& dir, nlohmann::json* metaOut) {
    const std::string metaPath = inDir(dir, "meta.json");
    nlohmann::json meta = readJsonFile(metaPath);
    checkGatherMeta(meta, metaPath);
    GatherOptions o = gatherOptionsFromJson(meta, metaPath);
    if (!o.anyColour)
        throw InputError(metaPath +
                         ": not an any-colour gather (\"any_colour\" is false or missing): its "
                         "paths were not recorded; gather again with weft gather --any-colour");
    if (metaOut) *metaOut = std::move(meta);
    return o;
}

}  // namespace

std::vector<ColourPath> loadColourPaths(const std::string& dir, GatherOptions* options) {
    const GatherOptions o = anyColourGatherOptions(dir, nullptr);
    if (options) *options = o;
    return readColourPaths(dir, o, o.paths);
}

RecolouredGather recolourGather(const std::string& dir, const Rgb& cTT) {
    const auto start = std::chrono::steady_clock::now();
    nlohmann::json meta;
    GatherOptions o = anyColourGatherOptions(dir, &meta);
    const JsonObjectReader r(meta, inDir(dir, "meta.json"));
    RecolouredGather result;
    result.gatheredCTT = o.fiber.cTT;
    GatherSums& sums = result.sums;
    sums = emptyGatherSums(o);
    // The records do not keep where paths left the ply: no exit distances.
    sums.sumExitDistance.clear();
    const RdmBins& b = o.bins;
    const size_t ti = b.thetaI, pi = b.phiI;
    addInt64Npy(inDir(dir, "count.npy"), {ti, pi}, sums.count);
    addInt64Npy(inDir(dir, "count_t.npy"), {ti, pi}, sums.countT);
    addInt64Npy(inDir(dir, "depth.npy"), {sums.depth.size()}, sums.depth);
    const int64_t counted = std::accumulate(sums.count.begin(), sums.count.end(), int64_t{0});
    const int64_t byDepth = std::accumulate(sums.depth.begin(), sums.depth.end(), int64_t{0});
    if (counted != o.paths || byDepth != o.paths)
        throw InputError(dir + ": count.npy and depth.npy must each sum to the gather's " +
                         std::to_string(o.paths) + " paths, got " + std::to_string(counted) +
                         " and " + std::to_string(byDepth));
    for (size_t i = 0; i < sums.count.size(); ++i)
        if (sums.countT[i] > sums.count[i])
            throw InputError(inDir(dir, "count_t.npy") + ": incident bin " + std::to_string(i) +
                             " has " + std::to_string(sums.countT[i]) + " T paths of " +
                             std::to_string(sums.count[i]));
    // The interacting paths: those not counted as T.
    const int64_t interacting = o.paths - sums.depth[0];
    const std::vector<ColourPath> paths = readColourPaths(dir, o, interacting);
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
