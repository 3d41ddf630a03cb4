// weft/gather/gather.h — the RDM gather: random walks through an explicit ply.
//
// Paper 4, 5.1-5.3; DESIGN.md 5. Every path starts on the ply's bounding
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
// i.e. exactly what eval(wi, wo) of that component must return (DESIGN.md 5).
//
// Determinism: path k draws from random stream k of the seed; weights are
// accumulated in 64-bit fixed point (2^-32 units) with atomic adds, which is
// associative, so the output is bit-identical for any thread count.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

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

    void validate() const;  // InputError naming the option
    uint64_t placementSeed() const { return plySeed.value_or(seed); }
};

struct GatherStats {
    int64_t paths = 0, rays = 0;
    int64_t truncatedPaths = 0;  // reached maxDepth
    int64_t axialPaths = 0;      // ran along the axis without hit or exit (recorded as exits)
    double meanDepth = 0;        // mean number of fiber interactions
    double truncatedEnergy[3] = {0, 0, 0};  // mean remaining weight per path
    double seconds = 0;      // whole gather: placement, BVH, walks, normalisation
    double walkSeconds = 0;  // the random walks alone
    int threads = 0;
    double period = 0, fiberRadius = 0;
    int64_t segments = 0, embreeBytes = 0;
};

struct GatherResult {
    RdmBins bins;
    std::vector<int64_t> count, countT;   // (TI, PI)
    std::vector<double> pT;                // (TI, PI), 0 where count == 0
    std::vector<float> rdmR, rdmM;         // (TI, PI, TO, PO, 3)
    std::vector<double> truncated;         // (TI, PI, 3): truncated weight / count
    std::vector<int64_t> depth;            // depth histogram, 0..maxDepth, then truncated
    std::vector<std::vector<Vec3>> plyLines;  // traced fiber centre lines
    double fiberRadius = 0;
    GatherStats stats;
};

GatherResult gatherRdm(const GatherOptions& options);

class TempDirCommit;

// Writes count.npy, count_t.npy, p_t.npy, rdm_r.npy, rdm_m.npy, truncated.npy,
// depth.npy, ply.txt and meta.json into the temporary directory and renames
// it into place. Create `out` before gathering so that an unwritable
// destination fails at once.
void writeGather(const GatherResult& result, const GatherOptions& options, TempDirCommit& out);
// The content of meta.json: inputs, bins, statistics, versions, array descriptions.
nlohmann::json gatherMetadata(const GatherResult& result, const GatherOptions& options);

}  // namespace weft
