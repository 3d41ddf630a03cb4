// weft/gather/gather_folder.h — a gather directory or a part of one, read and
// checked in one place. `weft fit`, `weft yarn check`, `weft rdm slice`
// (loadRdm, rdm_io.h), `weft gather merge` (gather_merge.h), `weft gather
// recolour` and the colour fit (colour_paths.h), and their Python twins read
// every file of a gather through here, so that each is checked once and the
// same way whichever command reads it:
//
//   meta.json  the format (a whole gather, "weft-gather", or a part,
//              "weft-gather-part") and version; every field that says what
//              was gathered (gatherOptionsFromJson: material, fiber, ply,
//              bins, paths, seeds, max depth, any_colour); the ply's
//              description (radius 1, fiber_radius R sqrt(density / fibers),
//              period 2R / twist, segments); a part's shard and statistics.
//   counts     count.npy, count_t.npy, depth.npy: int64 of the shapes the
//              bins and max depth give, every element in [0, paths], count
//              and depth summing to the paths, count_t <= count, depth[0] =
//              the T paths, and a part's depth_sum equal to its histogram's.
//   arrays     every other array's dtype and shape, each element finite and in
//              its range (readGatherArray; the ranges are the readers').
//   files      no two files read together (the files of one folder, or of
//              every part of a merge) are the same file: a symlink or a hard
//              link to another is refused (same device and inode).
//
// A merge or a recolouring writes a ply.txt and a ply description of its own,
// from the ply that the options give (emptyGatherSums); checkTracedPly
// requires the folder's to be exactly those.
//
// Anything else is an InputError naming the file, the field (its JSON path)
// or the element, and what is allowed.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "weft/gather/gather.h"

namespace weft {

enum class GatherFolderKind { Gather, Part };

// meta.json's "format" of a part (gather_merge.h); a whole gather's is "weft-gather".
inline constexpr const char* kGatherPartFormat = "weft-gather-part";

// One gather or part directory, its meta.json read and checked.
struct GatherFolder {
    GatherFolderKind kind = GatherFolderKind::Gather;
    std::string dir, metaPath;
    nlohmann::json meta;
    GatherOptions options;  // a part's: shard is its own

    // dir/name.
    std::string file(std::string_view name) const;
    // The paths its counts cover: the part's shard, or the whole gather.
    int64_t paths() const;
    // The files a reader of this folder reads, for checkDistinctFiles.
    std::vector<std::string> files() const;
    // Written with GatherFiles::Records (gather.h): an any-colour gather's
    // records without the RDM arrays of one colour and ply.txt.
    bool recordsOnly() const;
};

// InputError naming metaPath unless `meta` is a whole weft gather of format
// version 1; a part is told to merge first.
void checkGatherMeta(const nlohmann::json& meta, const std::string& metaPath);

// Reads DIR/meta.json as a folder of `kind` and checks it (above).
GatherFolder readGatherFolder(const std::string& dir, GatherFolderKind kind);

// What the N parts of one gather must agree on, as JSON paths in meta.json:
// every field gatherInputs() writes but the Embree version, and the shard
// count. mergeGatherParts compares them; a test checks that the list covers
// gatherInputs().
std::span<const std::string_view> sharedPartFields();
// The value at a dotted JSON path ("ply.radius"); null when absent.
nlohmann::json jsonAtPath(const nlohmann::json& meta, std::string_view path);

// InputError unless the folder's ply description (meta.json's "ply") and its
// ply.txt are exactly what the regenerated ply `traced` (emptyGatherSums of
// the folder's options) gives: the folder was traced on that ply.
void checkTracedPly(const GatherFolder& folder, const GatherSums& traced);

// InputError naming both paths when two of `paths` are one file (stat: the
// same device and inode, through symlinks and hard links). Paths that do
// not exist are skipped: their readers say so.
void checkDistinctFiles(const std::vector<std::string>& paths);

// count.npy, count_t.npy and depth.npy of a folder, checked (above).
struct GatherCounts {
    std::vector<int64_t> count, countT;  // (TI, PI)
    std::vector<int64_t> depth;          // (max_depth + 2)
    // Paths of incident bin i that met a fiber: count - count_t.
    int64_t interacting(size_t i) const { return count[i] - countT[i]; }
};
GatherCounts readGatherCounts(const GatherFolder& folder);

// The allowed range of an array's elements, for messages and checks.
struct ArrayRange {
    double lo = 0, hi = 0;
    const char* note = "";  // after the range: " (a probability)"
};

// The array in `path`: `descr` (<i8, <f8 or <f4) of `shape`, every element
// finite and in `range`, converted to T. InputError naming the file, the
// element (flat index and index tuple), its value and the range otherwise.
template <typename T>
std::vector<T> readGatherArray(const std::string& path, const char* descr,
                               const std::vector<size_t>& shape, const ArrayRange& range);

// "element 5 (0, 0, 1, 2)" of an array of `shape` ("element 5" when 1-D).
std::string gatherElementName(size_t k, const std::vector<size_t>& shape);

}  // namespace weft
