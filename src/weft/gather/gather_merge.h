// weft/gather/gather_merge.h — the shards of a gather on disk, and their exact merge
// (`weft gather --shard K/N`, `weft gather merge`; docs/cluster.md).
//
// Shard K of N walks the paths [floor(K P / N), floor((K + 1) P / N)) of a
// gather of P paths (core/shard.h); path k draws from random stream k of the
// seed whichever shard walks it. A shard writes a part directory (format
// "weft-gather-part", version 1) holding the gather's integer accumulators
// rather than its normalised float maps:
//   meta.json              what a gather's says it gathered (gatherInputs:
//                          material, fiber, ply, bins, paths of the whole
//                          gather, seeds, max_depth, versions), "shard":
//                          {"index", "count", "first_path", "end_path"} and
//                          this part's statistics ("rays", "axial_paths",
//                          "depth_sum", "elapsed_seconds", "walk_seconds", "threads")
//   count.npy, count_t.npy int64 (TI,PI): paths, and T paths, per incident bin
//   sum_r.npy, sum_m.npy   int64 (TI,PI,TO,PO,3): summed R / M path weights, in units of 2^-32
//   sum_truncated.npy      int64 (TI,PI,3): summed weight of paths cut at max_depth, 2^-32 units
//   sum_exit_distance.npy  int64 (129,3): summed M path weights by entry-to-exit distance
//   (gather.h) sum_exit_offset.npy    int64 (4,8,8193,3): the same by signed exit offset per
//   incident
//                          cell (gather.h); parts written before it have none, and a
//                          merge with such a part has none either
//   depth.npy              int64 (max_depth+2): paths by number of fiber interactions
//   ply.txt                the traced fiber centre lines, as a gather's
// `weft gather merge` adds the parts' integers and normalises once, with the
// code of an unsharded gather: every array of the merged directory is bit for
// bit the unsharded gather's, for any N and any order of the parts (meta.json
// differs in the timings and "shards"). The cost is size: the two sums take
// 8 bytes x 3 channels x TI PI TO PO each, 2 x 192 MB at the default bins.
#pragma once

#include <string>
#include <vector>

#include "weft/gather/gather.h"

namespace weft {

// Writes the part directory above for the sums of options.shard into `out`
// and renames it into place.
void writeGatherPart(const GatherSums& sums, const GatherOptions& options, TempDirCommit& out);

struct MergedGather {
    GatherOptions options;  // as the parts' meta.json say (shard: the whole gather)
    GatherSums sums;        // of every path of the gather
    int64_t shards = 0;
};

// Reads the part directories and adds them. They must be the N shards of one
// gather: each a "weft-gather-part" checked on its own (gather_folder.h:
// meta.json, counts, arrays, records), agreeing on every field of
// sharedPartFields() (material, fiber, ply and its description, bins, paths,
// seeds, max depth, any_colour, shard count, weft version), with shard
// indices 0..N-1 each exactly once, no file of one part a link to another
// file of any part, and each meta.json's ply description and ply.txt exactly
// those of the ply that the options give (the merge writes that ply).
// Anything else is an InputError naming the part's file and the field, row or
// element (a duplicate or missing shard names the shard and the parts given).
MergedGather mergeGatherParts(const std::vector<std::string>& partDirs);

// Adds the int64 array in the .npy file `path` to `into` element by element;
// InputError naming the file and the element unless it is <i8 of `shape`,
// every element is >= 0 (counts and weights) and the sums fit in int64.
void addInt64Npy(const std::string& path, const std::vector<size_t>& shape,
                 std::vector<int64_t>& into);

}  // namespace weft
