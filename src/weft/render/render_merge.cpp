#include "weft/render/render_merge.h"

#include <algorithm>
#include <limits>
#include <optional>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/image_io.h"
#include "weft/core/json_file.h"
#include "weft/core/json_reader.h"
#include "weft/core/limits.h"
#include "weft/core/shard.h"

namespace weft::render {

namespace {

struct Part {
    std::string exr, jsonPath;
    nlohmann::json stats;
    Shard shard;
    int64_t spp = 0, totalSpp = 0, first = 0;
    std::string checksum;  // shard.checksum: pixelChecksum of the image written
};

// "fnv1a64:" and 16 lower-case hex digits.
bool isPixelChecksum(const std::string& text) {
    const std::string prefix = "fnv1a64:";
    return text.size() == prefix.size() + 16 && text.compare(0, prefix.size(), prefix) == 0 &&
           std::all_of(text.begin() + prefix.size(), text.end(),
                       [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

Part readPart(const std::string& exr, const ReadPartFile& read) {
    Part p;
    p.exr = exr;
    p.jsonPath = renderStatsPath(exr, "part " + exr);
    // PART.json, or PART.render.json where PART.json was the render's scene.
    const std::string renamed = renamedRenderStatsPath(exr, "part " + exr);
    auto tryRead = [&](const std::string& path) -> std::optional<nlohmann::json> {
        try {
            return parseJsonText(read(path), path);
        } catch (const InputError&) {
            return std::nullopt;
        }
    };
    std::optional<nlohmann::json> stats = tryRead(p.jsonPath);
    if (!stats || (stats->is_object() && !stats->contains("spp")))
        if (std::optional<nlohmann::json> other = tryRead(renamed)) {
            stats = std::move(other);
            p.jsonPath = renamed;
        }
    // Neither: read PART.json again for its error.
    p.stats = stats ? std::move(*stats) : parseJsonText(read(p.jsonPath), p.jsonPath);
    const JsonObjectReader r(p.stats, p.jsonPath);
    if (!r.has("shard"))
        throw InputError(p.jsonPath +
                         ": a whole render, not a part of one (no \"shard\"): merge the images "
                         "that weft render --shard K/N wrote");
    r.string("mode");  // the merged statistics keep it
    const JsonObjectReader shard = r.object("shard");
    p.shard.count = shard.integer("count", {1, Shard::kMaxCount});
    p.shard.index = shard.integer("index", {0, p.shard.count - 1});
    p.totalSpp = shard.integer("spp", {p.shard.count, 1 << 20});
    p.first = shard.integer("first_sample", {0, p.totalSpp});
    p.spp = r.integer("spp", {1, p.totalSpp});
    if (p.first != p.shard.begin(p.totalSpp) || p.first + p.spp != p.shard.end(p.totalSpp) ||
        shard.integer("end_sample", {0, p.totalSpp}) != p.first + p.spp)
        throw InputError(p.jsonPath + ": shard " + p.shard.toString() + " of " +
                         std::to_string(p.totalSpp) + " spp covers samples [" +
                         std::to_string(p.shard.begin(p.totalSpp)) + ", " +
                         std::to_string(p.shard.end(p.totalSpp)) +
                         "), but \"spp\" and \"shard\" say otherwise");
    // Parts written before parts had a checksum cannot be told from damaged
    // ones: they are refused rather than merged unchecked (docs/cluster.md).
    if (!shard.has("checksum"))
        shard.fail("checksum",
                   "missing: the part has no checksum of its pixels (written by a weft before "
                   "render parts had one), so a damaged EXR could not be told from a good one; "
                   "render this part again (weft render --shard " +
                       p.shard.toString() + ")");
    p.checksum = shard.string("checksum");
    if (!isPixelChecksum(p.checksum))
        shard.fail("checksum", "expected \"fnv1a64:\" and 16 hex digits, got \"" +
                                   p.checksum.substr(0, 64) + "\"");
    return p;
}

// What the parts of one render share (keys of the statistics).
constexpr const char* kSharedKeys[] = {"scene_hash", "mode",          "width",
                                       "height",     "seed",          "max_depth",
                                       "next_event_estimation",       "yarn_sampling",
                                       "sampler",     "version"};

nlohmann::json sharedValue(const Part& p, const std::string& key) {
    if (key == "shard.count") return p.shard.count;
    if (key == "shard.spp") return p.totalSpp;
    return p.stats.contains(key) ? p.stats.at(key) : nlohmann::json();
}

}  // namespace

std::string renderStatsPath(const std::string& exr, const std::string& what) {
    const std::string ext = ".exr";
    if (exr.size() <= ext.size() || exr.compare(exr.size() - ext.size(), ext.size(), ext) != 0)
        throw InputError(what + ": expected a path ending in .exr (its statistics are the .json "
                                "beside it)");
    return exr.substr(0, exr.size() - ext.size()) + ".json";
}

std::string renamedRenderStatsPath(const std::string& exr, const std::string& what) {
    const std::string json = renderStatsPath(exr, what);
    return json.substr(0, json.size() - 5) + kRenderStatsSuffix;
}

MergedRender mergeRenderParts(const std::vector<std::string>& exrPaths) {
    return mergeRenderParts(exrPaths, [](const std::string& path) { return readFile(path); });
}

MergedRender mergeRenderParts(const std::vector<std::string>& exrPaths, const ReadPartFile& read) {
    if (exrPaths.empty()) throw InputError("no render parts to merge");
    std::vector<Part> parts;
    for (const std::string& exr : exrPaths) parts.push_back(readPart(exr, read));
    std::vector<std::string> keys(std::begin(kSharedKeys), std::end(kSharedKeys));
    keys.push_back("shard.count");
    keys.push_back("shard.spp");
    for (size_t k = 1; k < parts.size(); ++k)
        for (const std::string& key : keys) {
            const nlohmann::json a = sharedValue(parts[0], key), b = sharedValue(parts[k], key);
            if (a != b)
                throw InputError(parts[k].jsonPath + ": \"" + key + "\" is " + b.dump() + ", but " +
                                 parts[0].jsonPath + " has " + a.dump() +
                                 ": the parts are not shards of one render");
        }
    std::vector<Shard> shards;
    for (const Part& p : parts) shards.push_back(p.shard);
    checkCompleteShardSet(shards, exrPaths);

    const JsonObjectReader first(parts[0].stats, parts[0].jsonPath);
    const int width = static_cast<int>(first.integer("width", {1, 1 << 16}));
    const int height = static_cast<int>(first.integer("height", {1, 1 << 16}));
    // Allocated with the first image, whose size the reader has checked.
    std::vector<double> sum;
    nlohmann::json stats = parts[0].stats;
    int64_t passes = 0, rays = 0, nonFinite = 0, peak = 0, threads = 0, truncated = 0;
    // Parts by an older weft carry no truncation count: the merge then reports none.
    bool allCountTruncation = true;
    double seconds = 0, buildSeconds = 0;
    for (const Part& p : parts) {
        // The reader refuses NaN and infinite pixels (core/image_io.h).
        const Image image = decodeImage(read(p.exr), p.exr);
        if (image.width != width || image.height != height)
            throw InputError(p.exr + ": " + std::to_string(image.width) + " x " +
                             std::to_string(image.height) + " pixels, but " + p.jsonPath +
                             " says " + std::to_string(width) + " x " + std::to_string(height));
        if (const std::string checksum = pixelChecksum(image); checksum != p.checksum)
            throw InputError(p.exr + ": its pixels do not match the checksum in " + p.jsonPath +
                             " (shard.checksum " + p.checksum + ", the pixels read give " +
                             checksum + "): the part is damaged; render shard " +
                             p.shard.toString() + " again");
        if (sum.empty()) {
            // The sums, one image being read and the merged image with its
            // EXR and PNG encodings: a render's film (render/scene.cpp).
            checkMemoryBudget(static_cast<double>(width) * height * 56.0,
                              "merging render parts of " + std::to_string(width) + " x " +
                                  std::to_string(height) + " pixels");
            sum.assign(static_cast<size_t>(width) * height * 3, 0.0);
        }
        for (size_t i = 0; i < sum.size(); ++i)
            sum[i] += static_cast<double>(image.pixels[i]) * static_cast<double>(p.spp);
        const JsonObjectReader r(p.stats, p.jsonPath);
        passes += r.integer("passes", {0, 1 << 30});
        rays += r.integer("rays", {0, std::numeric_limits<int64_t>::max() / 65536});
        nonFinite += r.integer("non_finite_samples", {0, std::numeric_limits<int64_t>::max() / 65536});
        if (r.has("truncated_paths"))
            truncated +=
                r.integer("truncated_paths", {0, std::numeric_limits<int64_t>::max() / 65536});
        else
            allCountTruncation = false;
        peak = std::max(peak, r.integer("peak_resident_bytes", {0, std::numeric_limits<int64_t>::max()}));
        threads = std::max(threads, r.integer("threads", {1, 1024}));
        seconds += r.number("seconds", NumberRange::atLeast(0));
        buildSeconds += r.object("scene").number("build_seconds", NumberRange::atLeast(0));
    }
    MergedRender m;
    m.image = Image(width, height);
    const double spp = static_cast<double>(parts[0].totalSpp);
    for (size_t i = 0; i < sum.size(); ++i) m.image.pixels[i] = static_cast<float>(sum[i] / spp);

    stats.erase("shard");
    stats.erase("outputs");
    stats["spp"] = parts[0].totalSpp;
    stats["passes"] = passes;
    stats["seconds"] = seconds;
    stats["seconds_per_spp"] = seconds / spp;
    stats["rays"] = rays;
    stats["rays_per_second"] = seconds > 0 ? static_cast<double>(rays) / seconds : 0.0;
    stats["threads"] = threads;
    stats["peak_resident_bytes"] = peak;
    stats["non_finite_samples"] = nonFinite;
    if (allCountTruncation) {
        // One path per sample of every pixel.
        stats["truncated_paths"] = truncated;
        stats["truncated_fraction"] =
            static_cast<double>(truncated) / (spp * static_cast<double>(width) * height);
    } else {
        stats.erase("truncated_paths");
        stats.erase("truncated_fraction");
    }
    stats["scene"]["build_seconds"] = buildSeconds;
    stats["shards"] = {{"count", parts[0].shard.count}, {"parts", exrPaths}};
    m.stats = std::move(stats);
    return m;
}

}  // namespace weft::render
