// weft/gather/colour_paths.h — one gather for every C_TT (`weft gather --any-colour`,
// `weft gather recolour`; docs/gather.md, "Any colour from one gather").
//
// In the KSZ15 fiber (fiber_bcsdf.h) C_TT scales the TT lobe and nothing
// else. An any-colour gather picks the lobe at each fiber hit with the
// probability a white fiber (C_TT = 1) would use, p_R = mean_c F_c(theta_i),
// so no direction of the walk depends on C_TT, and weights each event by its
// own lobe (one-sample lobe selection):
//   R  event: F_c / p_R
//   TT event: (1 - F_c) C_TT,c / (1 - p_R)
// (both exact: each lobe's directions are sampled from that lobe alone). A
// path's weight in channel c is therefore W0_c C_TT,c^k, where k counts its TT
// events and W0 is its weight for C_TT = 1. C_R stays the material's, per
// channel, inside W0; C_TT may be any colour. Recording (incident bin,
// outgoing bin, kind, k, W0) for every path that interacts gives the RDM of
// every C_TT exactly (up to W0's float32 rounding, 6e-8 relative), without
// walking again: RDM_c(C_TT) = sum_paths W0_c C_TT,c^k / count / solid angle.
// T paths (no interaction) do not depend on the colour and are only counted.
//
// On disk, beside the usual arrays of a gather (which hold the material's
// own C_TT), one row per recorded path, in path order:
//   paths_bins.npy    int32 (N, 3): incident bin, outgoing bin (-1 for a
//                     truncated path), k = number of TT events
//   paths_kind.npy    uint8 (N): 0 R (one interaction, wo.n > 0), 1 M,
//                     2 truncated at max_depth
//   paths_weight.npy  float32 (N, 3): W0, the path's weight for C_TT = 1
// 25 bytes per path: 400 MB for the paper's 16M paths. Paths whose weight
// is 0 in every channel are not recorded.
#pragma once

#include <algorithm>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "weft/core/rgb.h"
#include "weft/gather/gather.h"
#include "weft/gather/gather_folder.h"

namespace weft {

// The lobe choice of an any-colour gather: the material's fiber with C_TT = 1.
FiberParams colourBlindFiber(const FiberParams& fiber);

// Adds `weight` of a path of `kind` to the sums (R, M or truncated map) with
// add(cell, value) where value is in the sums' fixed-point units; the one
// place where a path meets the accumulators.
template <typename Add>
void addPathWeight(GatherSums& sums, ColourPath::Kind kind, size_t incidentBin, size_t outgoingBin,
                   const Rgb& weight, Add&& add) {
    std::vector<int64_t>& map = kind == ColourPath::R   ? sums.sumR
                                : kind == ColourPath::M ? sums.sumM
                                                        : sums.sumTruncated;
    const size_t cell = kind == ColourPath::Truncated
                            ? incidentBin * 3
                            : (incidentBin * sums.bins.outgoingCount() + outgoingBin) * 3;
    for (int c = 0; c < 3; ++c) add(map[cell + c], GatherSums::toFixed(weight[c]));
}

// The recorded path's weight for cTT, added to `sums` with add().
template <typename Add>
void addColourPath(GatherSums& sums, const ColourPath& p, const Rgb& cTT, Add&& add) {
    const Rgb w(p.weightFor(cTT, 0), p.weightFor(cTT, 1), p.weightFor(cTT, 2));
    addPathWeight(sums, p.kind, static_cast<size_t>(p.incidentBin),
                  static_cast<size_t>(std::max(p.outgoingBin, 0)), w, add);
}

// meta.json's descriptions of the three arrays above.
nlohmann::json colourPathArrayDescriptions();
// The three arrays above, row-major.
struct ColourPathColumns {
    std::vector<int32_t> bins;   // (N, 3)
    std::vector<uint8_t> kinds;  // (N)
    std::vector<float> weights;  // (N, 3)
};
ColourPathColumns colourPathColumns(const std::vector<ColourPath>& paths);
// Writes the three paths_*.npy arrays into `dir`.
void writeColourPaths(const std::string& dir, const std::vector<ColourPath>& paths);
// The largest W0 a record may hold: W0 2^32 is an int64 (GatherSums::toFixed).
inline constexpr float kMaxRecordWeight = 2147483648.0f;  // 2^31, excluded
// Reads them back from a gather or part folder (gather_folder.h) and checks
// every row against its options (bins, max depth) and counts (at most
// count - count_t records per incident bin), each weight in [0, 2^31), and
// that the fixed-point sums of every colour hold them (no cell's summed W0
// beyond 2^31, in 2^-32 units): InputError naming the file, the row and the
// allowed range.
std::vector<ColourPath> readColourPaths(const GatherFolder& folder, const GatherCounts& counts);

// The recorded paths of the any-colour gather directory `dir`, and its
// options; InputError naming meta.json when the gather is not one (made
// without --any-colour, or a shard), or naming the file of a damaged record.
std::vector<ColourPath> loadColourPaths(const std::string& dir, GatherOptions* options = nullptr);

struct RecolouredGather {
    GatherSums sums;
    GatherOptions options;  // the gather's, with fiber.cTT the new colour and anyColour false
    Rgb gatheredCTT;        // the colour of the directory's own arrays
};

// The sums of the any-colour gather directory `dir` with every weight for
// cTT instead of the gathered colour: count, count_t and depth from its
// arrays, the R, M and truncated sums from its recorded paths.
// normaliseGather(sums, options) is then the gather that the same walks
// give for that colour; for the gathered colour it is bit for bit the
// directory's own arrays. InputError naming the file when the directory was
// not gathered with --any-colour, or its arrays disagree with each other.
RecolouredGather recolourGather(const std::string& dir, const Rgb& cTT);

}  // namespace weft
