// weft/render/render_merge.h — the parts of a sharded render and their merge
// (`weft render --shard K/N`, `weft render merge`; docs/cluster.md).
//
// A part is what `weft render SCENE --spp S --shard K/N --out PART.exr` writes:
// PART.exr, the mean of samples [floor(K S / N), floor((K + 1) S / N)) of
// every pixel (renderer.h), and PART.json, its statistics with "shard":
// {"index", "count", "spp" (S, of the whole render), "first_sample",
// "end_sample", "checksum"}. The checksum is pixelChecksum (core/image.h) of
// the image written: the merge refuses a part whose pixels read back to
// another (a damaged EXR may still decode), and a part without one (written
// before parts had one: render it again). The merge is the sample-weighted mean
//     image = sum_k n_k image_k / sum_k n_k,     n_k = end_sample - first_sample,
// computed in double, which is the unsharded image up to float rounding
// (each part is stored as float32: a relative 2^-24 per part).
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "weft/core/image.h"

namespace weft::render {

// PART.exr -> PART.json (the statistics beside an image); InputError naming
// `what` unless `exr` ends in .exr.
std::string renderStatsPath(const std::string& exr, const std::string& what);
// Where PART.json is the render's own scene file, the statistics go to
// PART.render.json instead (weft render; docs/render.md): the merge reads
// that one when PART.json is missing or holds no render statistics (no "spp").
inline constexpr const char* kRenderStatsSuffix = ".render.json";
// PART.exr -> PART.render.json; the same check of `exr` as renderStatsPath.
std::string renamedRenderStatsPath(const std::string& exr, const std::string& what);

struct MergedRender {
    Image image;
    // The parts' statistics merged: spp, passes, seconds, rays and
    // non-finite samples summed over the parts, threads and peak memory the
    // largest, rates recomputed; "shards": {"count", "parts"}; no "outputs".
    nlohmann::json stats;
};

// Reads the parts (each EXR and the JSON beside it) and merges them. They
// must be the N shards of one render: the same scene hash, mode, size, seed,
// max depth, next-event estimation, yarn sampling, weft version and total
// spp, shards 0..N-1 each once, images of the size the statistics say with
// finite pixels that match the part's checksum. Anything else is an
// InputError naming the part and the field. The merged sums are allocated
// once the first image has been read and matched its statistics (within the
// memory budget, core/limits.h), not from what a JSON claims.
MergedRender mergeRenderParts(const std::vector<std::string>& exrPaths);

// The same, reading each file's bytes through `read` (given a path, its
// contents; an InputError naming it otherwise): readFile (core/file.h) above,
// bytes in memory in the fuzz harness (fuzz/render_part_fuzz.cpp).
using ReadPartFile = std::function<std::string(const std::string& path)>;
MergedRender mergeRenderParts(const std::vector<std::string>& exrPaths, const ReadPartFile& read);

}  // namespace weft::render
