// weft/gather/family.h — a family gather: the random walks of many plies whose
// yarn parameters spread over a box (issue 42; docs/family.md).
//
// A family model gives the yarn BSDF anywhere in a box of yarn parameters
// without a gather or a fit per yarn. Its data are the walks of K yarns of
// the box: point k of a scrambled Halton sequence in the box's unit cube
// (one dimension per parameter, C_R taking three: one per channel) is a ply
// (N fibers, density rho, twist alpha) of fibers (beta_R, beta_TT, gamma_TT,
// C_R), and an any-colour gather of P paths through it (gather.h,
// colour_paths.h: C_TT stays free, as in a colour model). Each point is a
// gather folder, DIR/points/NNNNN/, whose walks and ply come from the point's
// own seed: its files are exactly those of `weft gather --any-colour` of that
// yarn with that seed (FamilyGatherOptions::pointOptions), less the RDM
// arrays of one colour and the traced fibers (GatherFiles::Records: K
// points would hold K copies of them). `weft gather recolour` turns a point
// into the full gather of any C_TT, which every other tool reads.
//
// Sharding: shard K of N (a Slurm array, docs/cluster.md) gathers the points
// [floor(K T / N), floor((K + 1) T / N)); the shards of one family write into
// the same DIR at once, each point folder written whole and renamed into
// place, and DIR/family.json (the same text from every shard). A point folder
// that is already there with the same inputs is kept: a rerun completes a
// family. loadFamilyGather() reads a complete one.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "weft/core/family_box.h"
#include "weft/core/rgb.h"
#include "weft/core/shard.h"
#include "weft/fiber/fiber_params.h"
#include "weft/gather/gather.h"
#include "weft/gather/rdm.h"
#include "weft/ply/ply.h"

namespace weft {

// Point p's ply, and its fiber with colour cTT.
inline PlyParams plyOf(const YarnPoint& p) { return {p.fibers, p.density, p.twist}; }
inline FiberParams fiberOf(const YarnPoint& p, const Rgb& cTT) {
    return {p.cR, cTT, p.betaRDeg, p.betaTTDeg, p.gammaTTDeg};
}

// InputError naming `source` unless the box's corners are a ply and a fiber
// (PlyParams, FiberParams: then so is every point between them), after FamilyBox::validate.
void validateFamilyBox(const FamilyBox& box, const std::string& source);

// The most points of one family.
constexpr int kMaxFamilyPoints = 65536;

struct FamilyGatherOptions {
    FamilyBox box;
    int points = 0;                // [1, kMaxFamilyPoints]
    int64_t pathsPerPoint = 0;     // [1, kMaxPaths]
    uint64_t seed = 0;             // the points and every point's walks
    FamilyDesign design = FamilyDesign::Halton;  // how the points spread (core/family_box.h)
    RdmBins bins{11, 45, 15, 30};  // the fit's error grid (fit/metrics.h, kCoarseErrorBins)
    int maxDepth = 1000, threads = 0, segmentsPerTwist = 128;
    bool quiet = false;
    Shard shard;  // of the points

    void validate() const;  // InputError naming the option
    // The gather of point k: any colour (recorded at C_TT 0.5 grey), its
    // walks and fiber placement from the point's seed.
    GatherOptions pointOptions(int k, const YarnPoint& p) const;
    // "points/0007": point k's folder under the family's.
    static std::string pointFolder(int k);
};

struct FamilyGatherSummary {
    int pointsGathered = 0, pointsKept = 0;  // of this shard
    int64_t paths = 0;                       // walked here
    double seconds = 0;
};

// The summary line of weft gather family (and the dict of weft.gather_family):
// out, points, shard, first_point, end_point, points_gathered, points_kept,
// paths, seconds.
nlohmann::json familyGatherSummaryJson(const FamilyGatherOptions& options,
                                       const FamilyGatherSummary& summary, const std::string& dir);

// Gathers the points of options.shard into DIR (created if missing) and
// writes DIR/family.json; keeps a point folder already there with the same
// inputs and refuses (InputError naming it) one with other inputs.
FamilyGatherSummary gatherFamily(const FamilyGatherOptions& options, const std::string& dir);

// DIR/family.json: the box, the options and every point ("design" only when
// it is not halton, so that the files of earlier families stay as they were).
nlohmann::json familyMetadata(const FamilyGatherOptions& options,
                              const std::vector<YarnPoint>& points);

// A complete family gather, read back.
struct FamilyGather {
    std::string dir;
    FamilyGatherOptions options;
    std::vector<YarnPoint> points;
    std::string pointDir(int k) const;  // DIR/points/NNNN
};

// Reads DIR/family.json and checks that every point's folder is there with
// its inputs; InputError naming the file, the field, or the missing points
// (and which shards of N hold them).
FamilyGather loadFamilyGather(const std::string& dir);

}  // namespace weft
