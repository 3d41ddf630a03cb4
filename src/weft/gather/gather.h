// weft/gather/gather.h — the RDM gather: random walks through an explicit ply.
//
// Paper 4, 5.1-5.3; docs/design.md 5. Every path starts on the ply's bounding
// cylinder (radius R = 1), uniformly over the circumference and over one
// twist period along the axis, with wi uniform over the upper hemisphere of
// the entry frame (t = +z, n = outward radial, b = t x n), and travels along
// -wi into the ply. At each fiber hit wo is sampled from the fiber BCSDF in
// that fiber's frame (tangent of its helix at the hit); the RGB weight is
// multiplied by the sample weight. The path ends when it leaves the cylinder;
// its exit direction is binned in the entry frame with label T (no
// interaction), R (one interaction, wo.n > 0) or M (everything else).
// Paths that would need more than maxDepth interactions are truncated and
// their remaining energy reported.
//
//   count(i)      paths per incident bin       p_t(i) = count_t(i) / count(i)
//   rdm_c(i, o)   sum of label-c weights / count(i) / solidAngle(o)  (c = R, M)
// i.e. exactly what eval(wi, wo) of that component must return (docs/design.md 5).
//
// Determinism: path k draws from random stream k of the seed; weights are
// accumulated in 64-bit fixed point (2^-32 units) with atomic adds, which is
// associative, so the output is bit-identical for any thread count, and for
// any split of the paths into shards (GatherOptions::shard) whose integer
// sums are added before normalising (gather_merge.h).
#pragma once

#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "weft/core/exit_offset.h"
#include "weft/core/rgb.h"
#include "weft/core/shard.h"
#include "weft/fiber/fiber_params.h"
#include "weft/gather/rdm.h"
#include "weft/ply/ply.h"

namespace weft {

// The most random walks of one gather: the RDM's fixed-point accumulators
// (2^-32 units in int64) hold 2^31 unit-weight paths per cell.
constexpr int64_t kMaxPaths = int64_t{1} << 31;

struct GatherOptions {
    FiberParams fiber;
    PlyParams ply;
    std::string material;  // preset name, or the params file, for the record
    int64_t paths = 0;     // in [1, kMaxPaths]
    uint64_t seed = 0;                  // random walks (and fiber placement unless plySeed is set)
    std::optional<uint64_t> plySeed;    // fiber placement; default: seed
    RdmBins bins;
    int maxDepth = 1000;         // fiber interactions allowed per path, >= 1
    int threads = 0;             // 0: all cores
    int segmentsPerTwist = 128;  // helix resolution of the traced geometry
    bool quiet = false;          // no progress output
    // The paths this run walks: [shard.begin(paths), shard.end(paths)) of the
    // `paths` of the whole gather (all of them by default).
    Shard shard;
    // Colour-blind lobe choice and one record per interacting path, from
    // which the RDM of any C_TT follows (colour_paths.h).
    bool anyColour = false;

    void validate() const;  // InputError naming the option
    uint64_t placementSeed() const { return plySeed.value_or(seed); }
};

// One interacting path of an any-colour gather (colour_paths.h).
struct ColourPath {
    enum Kind : uint8_t { R = 0, M = 1, Truncated = 2 };
    int32_t incidentBin = 0;
    int32_t outgoingBin = -1;  // -1 for Truncated
    int32_t ttEvents = 0;      // k, the number of TT events
    Kind kind = M;
    float weight[3] = {0, 0, 0};  // W0: the path's weight for C_TT = 1

    // W0_c C_TT,c^k in channel c: the one formula of a gather and a recolouring.
    double weightFor(const Rgb& cTT, int c) const {
        return static_cast<double>(weight[c]) * std::pow(cTT[c], ttEvents);
    }
    bool operator==(const ColourPath&) const = default;
};

// M paths by how far they travel in the ply: the distance between their
// entry and exit points on the bounding cylinder, along its surface
// (sqrt(dz^2 + (R dpsi)^2) with z unwrapped across twist periods and dpsi in
// [-pi, pi]), in ply radii. Bins of kExitDistanceBinWidth up to
// kExitDistanceBins of them, then one for everything farther (and for paths
// that ran along the axis). The model assumes light leaves where it enters
// (paper 8, "Limitations"); this measures how far from true that is.
inline constexpr int kExitDistanceBins = 128;
inline constexpr double kExitDistanceBinWidth = 0.125;

// The bin of distance d (>= 0): [0, kExitDistanceBins].
inline int exitDistanceBin(double d) {
    return d < kExitDistanceBins * kExitDistanceBinWidth
               ? static_cast<int>(d / kExitDistanceBinWidth)
               : kExitDistanceBins;
}

// M paths by where they leave the ply relative to where they entered, signed
// (issue 47, docs/exit-point.md): per incident cell of the entry frame, the
// M weight per slot of the offset (dz along the axis, dpsi around it), the
// layout of core/exit_offset.h. A ply-level model that moves the exit point
// (paper 8, "Limitations") samples from these. The arrays' shape:
// {kExitOffsetTheta, kExitOffsetPhi, kExitOffsetSlots, 3}.
std::vector<size_t> exitOffsetShape();

// One channel of the M paths of a band of theta_i (all its phi_i cells) in
// GatherResult::exitOffset: their weight, the share beyond the axial range,
// and over the rest (bin centres) the means, standard deviations and the
// correlation of dz and dpsi.
struct ExitOffsetSummary {
    double weight = 0, beyondFraction = 0;
    double meanAxial = 0, meanAround = 0, sdAxial = 0, sdAround = 0, correlation = 0;
};
ExitOffsetSummary summarizeExitOffset(const std::vector<double>& histogram, int thetaBand,
                                      int channel);

// One channel of GatherResult::exitDistance: the M weight, the weighted
// mean distance of the paths within the binned range, the median and 90th
// percentile (linear within a bin), and the share of weight beyond it.
struct ExitDistanceSummary {
    double weight = 0, mean = 0, median = 0, p90 = 0, beyondFraction = 0;
};
ExitDistanceSummary summarizeExitDistance(const std::vector<double>& histogram, int channel);

struct GatherStats {
    int64_t paths = 0, rays = 0;  // paths: of the whole gather
    int64_t truncatedPaths = 0;  // reached maxDepth
    int64_t axialPaths = 0;      // ran along the axis without hit or exit (recorded as exits)
    double meanDepth = 0;        // mean number of fiber interactions
    double truncatedEnergy[3] = {0, 0, 0};  // mean remaining weight per path
    double seconds = 0;      // whole gather: placement, BVH, walks, normalisation
    double walkSeconds = 0;  // the random walks alone
    int threads = 0;
    // A merge of shards: their number; seconds, walkSeconds and rays are
    // their sums, threads the largest.
    int64_t shards = 1;
    double period = 0, fiberRadius = 0;
    int64_t segments = 0, embreeBytes = 0;
};

struct GatherResult {
    RdmBins bins;
    std::vector<int64_t> count, countT;   // (TI, PI)
    std::vector<double> pT;                // (TI, PI), 0 where count == 0
    std::vector<float> rdmR, rdmM;         // (TI, PI, TO, PO, 3)
    // (TI, PI, TO, PO, 3): RDM_M with wo in the exit frame (the yarn frame
    // where the path left the ply, docs/exit-point.md) instead of the entry
    // frame; empty where not recorded.
    std::vector<float> rdmMExit;
    std::vector<double> truncated;         // (TI, PI, 3): truncated weight / count
    std::vector<int64_t> depth;            // depth histogram, 0..maxDepth, then truncated
    // (kExitDistanceBins + 1, 3): M weight per path exiting at each distance
    // (their sum is the M albedo averaged over the gather's incident directions).
    std::vector<double> exitDistance;
    // (kExitOffsetTheta, kExitOffsetPhi, kExitOffsetSlots, 3): M weight per
    // path by signed exit offset, per incident cell; empty where not recorded.
    std::vector<double> exitOffset;
    std::vector<std::vector<Vec3>> plyLines;  // traced fiber centre lines
    double fiberRadius = 0;
    std::vector<ColourPath> colourPaths;   // any-colour gathers (colour_paths.h)
    GatherStats stats;
};

// The integer accumulators of a gather, or of one shard of it. Adding the
// sums of disjoint shards gives the sums of their union exactly (integers),
// so normalising the sum of all N shards gives the unsharded gather bit for bit.
struct GatherSums {
    RdmBins bins;
    int64_t firstPath = 0, endPath = 0;   // the paths walked: [firstPath, endPath)
    std::vector<int64_t> count, countT;   // (TI, PI)
    std::vector<int64_t> sumR, sumM;      // (TI, PI, TO, PO, 3): weights in 2^-32 units
    std::vector<int64_t> sumTruncated;    // (TI, PI, 3): weights in 2^-32 units
    std::vector<int64_t> sumExitDistance;  // (kExitDistanceBins + 1, 3): M weights, 2^-32 units
    // (kExitOffsetTheta, kExitOffsetPhi, kExitOffsetSlots, 3): M weights,
    // 2^-32 units; empty where not recorded (recoloured gathers, parts written
    // before it existed).
    std::vector<int64_t> sumExitOffset;
    // (TI, PI, TO, PO, 3): sumM binned by wo in the exit frame; empty where
    // not recorded (as sumExitOffset).
    std::vector<int64_t> sumMExit;
    std::vector<int64_t> depth;           // depth histogram, 0..maxDepth, then truncated
    int64_t rays = 0, axialPaths = 0, depthSum = 0;
    double seconds = 0, walkSeconds = 0;  // of the walks and their set-up
    int threads = 0;
    // The traced ply, the same for every shard of a gather.
    std::vector<std::vector<Vec3>> plyLines;  // fiber centre lines
    double period = 0, fiberRadius = 0;
    int64_t segments = 0, embreeBytes = 0;
    // Any-colour gathers: the interacting paths with a non-zero weight, in path order.
    std::vector<ColourPath> colourPaths;

    // One unit of sumR, sumM and sumTruncated: 2^-32 resolves weights to
    // 2.3e-10 and leaves room for 2^31 unit-weight paths in one cell.
    static constexpr double kFixedScale = 4294967296.0;
    static int64_t toFixed(double w) { return std::llround(w * kFixedScale); }
};

// Zero sums for the bins and depth of `options`, with the ply's description
// (which builds the ply's geometry).
GatherSums emptyGatherSums(const GatherOptions& options);
// The walks of options.shard; gatherRdm(o) is normaliseGather(gatherSums(o), o).
GatherSums gatherSums(const GatherOptions& options);
// The RDM of the sums of the whole gather (every path of options.paths), with
// the ply's centre lines and statistics; `shards` and the times as GatherStats says.
GatherResult normaliseGather(GatherSums sums, const GatherOptions& options,
                             int64_t shards = 1);
GatherResult gatherRdm(const GatherOptions& options);

class TempDirCommit;

// What writeGather writes: everything, or (a family's point, family.h) the
// records an any-colour gather needs for any C_TT, without the RDM arrays of
// one colour (rdm_r.npy, rdm_m.npy) and the traced fibers (ply.txt).
// A gather of records says so in its meta.json: "files": kGatherRecordsOnly.
enum class GatherFiles { All, Records };
inline constexpr const char* kGatherRecordsOnly = "records";

// Writes count.npy, count_t.npy, p_t.npy, rdm_r.npy, rdm_m.npy, truncated.npy,
// depth.npy, exit_distance.npy, exit_offset.npy and rdm_m_exit.npy (not with
// Records), ply.txt,
// the paths_*.npy of an any-colour gather and meta.json
// (gatherMetadata updated with `extraMeta`) into the temporary directory and
// renames it into place. Create `out` before gathering so that an
// unwritable destination fails at once.
void writeGather(const GatherResult& result, const GatherOptions& options, TempDirCommit& out,
                 const nlohmann::json& extraMeta = nlohmann::json::object(),
                 GatherFiles files = GatherFiles::All);
// ply.txt: the traced fiber centre lines as a curve file (core/curves.h).
void writePlyLines(const std::string& path, const std::vector<std::vector<Vec3>>& lines,
                   double fiberRadius);
// The text writePlyLines writes (`path` names it in errors).
std::string formatPlyLines(const std::vector<std::vector<Vec3>>& lines, double fiberRadius,
                           const std::string& path);
// The content of meta.json: inputs, bins, statistics, versions, array descriptions.
nlohmann::json gatherMetadata(const GatherResult& result, const GatherOptions& options);
// The part of meta.json that says what was gathered (material, fiber, ply,
// bins, paths, seeds, max_depth) and by which versions; the shards of one
// gather share it (gather_merge.h).
nlohmann::json gatherInputs(const GatherOptions& options, double fiberRadius, double period,
                            int64_t segments);
// The options gatherInputs() wrote (shard: the whole gather); InputError
// naming `metaPath` and the field when one is missing or out of range.
GatherOptions gatherOptionsFromJson(const nlohmann::json& meta, const std::string& metaPath);

}  // namespace weft
