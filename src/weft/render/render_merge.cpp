#include "weft/render/render_merge.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "weft/core/error.h"
#include "weft/core/image_io.h"
#include "weft/core/json_file.h"
#include "weft/core/json_reader.h"
#include "weft/core/shard.h"

namespace weft::render {

namespace {

struct Part {
    std::string exr, jsonPath;
    nlohmann::json stats;
    Shard shard;
    int64_t spp = 0, totalSpp = 0, first = 0;
};

Part readPart(const std::string& exr) {
    Part p;
    p.exr = exr;
    p.jsonPath = renderStatsPath(exr, "part " + exr);
    p.stats = readJsonFile(p.jsonPath);
    const JsonObjectReader r(p.stats, p.jsonPath);
    if (!r.has("shard"))
        throw InputError(p.jsonPath +
                         ": a whole render, not a part of one (no \"shard\"): merge the images "
                         "that weft render --shard K/N wrote");
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

MergedRender mergeRenderParts(const std::vector<std::string>& exrPaths) {
    if (exrPaths.empty()) throw InputError("no render parts to merge");
    std::vector<Part> parts;
    for (const std::string& exr : exrPaths) parts.push_back(readPart(exr));
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
    std::vector<double> sum(static_cast<size_t>(width) * height * 3, 0.0);
    nlohmann::json stats = parts[0].stats;
    int64_t passes = 0, rays = 0, nonFinite = 0, peak = 0, threads = 0, truncated = 0;
    // Parts by an older weft carry no truncation count: the merge then reports none.
    bool allCountTruncation = true;
    double seconds = 0, buildSeconds = 0;
    for (const Part& p : parts) {
        const Image image = readImage(p.exr);
        if (image.width != width || image.height != height)
            throw InputError(p.exr + ": " + std::to_string(image.width) + " x " +
                             std::to_string(image.height) + " pixels, but " + p.jsonPath +
                             " says " + std::to_string(width) + " x " + std::to_string(height));
        for (size_t i = 0; i < sum.size(); ++i) {
            if (!std::isfinite(image.pixels[i]))
                throw InputError(p.exr + ": pixel " + std::to_string(i / 3) +
                                 " is not finite (a render part never is)");
            sum[i] += static_cast<double>(image.pixels[i]) * static_cast<double>(p.spp);
        }
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
