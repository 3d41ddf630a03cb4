#include "weft/render/renderer.h"

#include <sys/resource.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <tuple>

#include "weft/core/error.h"
#include "weft/core/progress.h"

namespace weft::render {

namespace {

constexpr int kTile = kRenderTile;

// The generator of sample `sample` of pixel `pixel`: independent of passes and threads.
Rng sampleRng(uint64_t pixel, int64_t sample, uint64_t seed) {
    return Rng(pixel,
               mixBits(seed ^ mixBits(static_cast<uint64_t>(sample) + 0x9e3779b97f4a7c15ULL)));
}

}  // namespace

void RenderOptions::validate() const {
    if ((spp > 0) == (seconds > 0))
        throw InputError("give exactly one budget: --spp N (N >= 1) or --time SECONDS (> 0)");
    if (spp < 0 || spp > (1 << 20))
        throw InputError("--spp " + std::to_string(spp) + " is out of range: allowed [1, 1048576]");
    if (!std::isfinite(seconds) || seconds < 0 || seconds > 1e6)
        throw InputError("--time " + std::to_string(seconds) +
                         " is out of range: allowed (0, 1e6] seconds");
    checkRange("--threads", threads, 0, 1024, " (0: all cores)");
    checkRange("max_depth", maxDepth, 1, 10000);
    if (checkpointSeconds != 0 &&
        (!std::isfinite(checkpointSeconds) || checkpointSeconds < 0.1 || checkpointSeconds > 1e6))
        throw InputError("--checkpoint " + std::to_string(checkpointSeconds) +
                         " is out of range: allowed [0.1, 1e6] seconds");
    if (aovs != 0 && shard)
        throw InputError(
            "--aov does not apply to --shard parts: weft render merge merges the image "
            "only; render the passes in one process");
    if (shard) {
        if (spp == 0)
            throw InputError("--shard needs --spp: a time budget has no fixed range of samples "
                             "to split");
        shard->validate(spp, "--shard", "samples per pixel");
    }
    if (rows && (rows->first < 0 || rows->first % kRenderTile != 0 || rows->second <= rows->first ||
                 shard || aovs != 0))
        throw InputError("rows [" + std::to_string(rows->first) + ", " +
                         std::to_string(rows->second) +
                         "): allowed a first row that is a multiple of " +
                         std::to_string(kRenderTile) + " below the end, and no --shard or --aov");
    if (samples) {
        if (shard || spp == 0 || aovs != 0)
            throw InputError("a sample range needs --spp, and no --shard or --aov");
        if (samples->first < 0 || samples->first >= samples->second || samples->second > spp)
            throw InputError("samples [" + std::to_string(samples->first) + ", " +
                             std::to_string(samples->second) +
                             ") is out of range: allowed 0 <= first < end <= spp (" +
                             std::to_string(spp) + ")");
    }
}

const char* aovName(Aov aov) {
    switch (aov) {
        case kAovAlbedo:
            return "albedo";
        case kAovNormal:
            return "normal";
        case kAovDepth:
            return "depth";
        case kAovYarnId:
            return "yarn_id";
    }
    return "?";
}

const char* pathIntegratorName(PathIntegrator integrator) {
    switch (integrator) {
        case PathIntegrator::Auto:
            return "auto";
        case PathIntegrator::PerPath:
            return "path";
        case PathIntegrator::Batched:
            return "batch";
    }
    return "?";
}

PathIntegrator parsePathIntegrator(const std::string& name, const std::string& what) {
    for (const PathIntegrator integrator :
         {PathIntegrator::Auto, PathIntegrator::PerPath, PathIntegrator::Batched})
        if (name == pathIntegratorName(integrator)) return integrator;
    throw InputError(what + " \"" + name + "\" is not an integrator: allowed auto, path, batch");
}

unsigned parseAovs(const std::string& list) {
    unsigned mask = 0;
    size_t start = 0;
    while (start <= list.size()) {
        const size_t comma = std::min(list.find(',', start), list.size());
        const std::string name = list.substr(start, comma - start);
        bool known = false;
        for (const Aov aov : kAovs)
            if (name == aovName(aov)) mask |= aov, known = true;
        if (!known)
            throw InputError("--aov \"" + name +
                             "\" is not a pass: allowed albedo, normal, depth, "
                             "yarn_id (comma-separated)");
        start = comma + 1;
    }
    return mask;
}

SamplerKind parseSampler(const std::string& name, const std::string& field) {
    if (const std::optional<SamplerKind> kind = samplerKindFromName(name)) return *kind;
    std::string allowed;
    for (const SamplerKind k : kSamplerKinds)
        allowed += (allowed.empty() ? "" : ", ") + std::string(samplerKindName(k));
    throw InputError(field + " \"" + name + "\" is not a sampler: allowed " + allowed);
}

int64_t peakResidentBytes() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return static_cast<int64_t>(usage.ru_maxrss) * 1024;  // Linux reports KiB
}

RenderResult render(const Scene& scene, const RenderOptions& options) {
    options.validate();
    // Without next-event estimation a point or directional light would
    // silently light nothing: no BSDF sample can reach it.
    if (!options.nextEventEstimation)
        for (size_t i = 0; i < scene.lights().size(); ++i)
            if (scene.lights()[i]->isDelta())
                throw InputError("lights[" + std::to_string(i) +
                                 "] is a point or directional light, which only next-event "
                                 "estimation reaches: render without --no-nee");
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    auto secondsSince = [](Clock::time_point t) {
        return std::chrono::duration<double>(Clock::now() - t).count();
    };
    const Camera& camera = scene.camera();
    const int width = scene.width(), height = scene.height();
    const int tilesX = (width + kTile - 1) / kTile, tilesY = (height + kTile - 1) / kTile;
    // The tiles [firstTile, endTile) of the rows asked for (all by default).
    if (options.rows && options.rows->second > height)
        throw InputError("rows [" + std::to_string(options.rows->first) + ", " +
                         std::to_string(options.rows->second) + ") end below the image's " +
                         std::to_string(height) + " rows");
    const int tiles = tilesX * tilesY;
    const int firstTile = options.rows ? options.rows->first / kTile * tilesX : 0;
    const int endTile = options.rows ? (options.rows->second + kTile - 1) / kTile * tilesX : tiles;
    std::vector<double> sum(static_cast<size_t>(width) * height * 3, 0.0);
    // Samples per pixel each tile has traced: all the same unless stopped in a pass.
    std::vector<int64_t> tileSamples(static_cast<size_t>(tiles), 0);
    std::atomic<uint64_t> rays{0}, nonFinite{0}, paths{0}, truncated{0};
    std::atomic<bool> stopped{false};
    // The passes' sums (3 albedo, 3 normal, 1 depth per pixel) and each
    // pixel's first sample's id.
    const bool withAovs = options.aovs != 0;
    std::vector<double> passSum(withAovs ? static_cast<size_t>(width) * height * 7 : 0, 0.0);
    std::vector<int> passId(withAovs ? static_cast<size_t>(width) * height : 0, 0);

    const bool batched = options.integrator == PathIntegrator::Batched ||
                         (options.integrator == PathIntegrator::Auto && scene.batchesFaster());
    PathTracerOptions tracer;
    tracer.maxDepth = options.maxDepth;
    tracer.nextEventEstimation = options.nextEventEstimation;

    const int threads =
        options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
    tbb::task_arena arena(threads);
    const bool timed = options.spp == 0;
    // Samples [first, last) of every pixel, for a part its shard's.
    int64_t first = options.shard ? options.shard->begin(options.spp) : 0;
    int64_t last = timed ? 0 : (options.shard ? options.shard->end(options.spp) : options.spp);
    if (options.samples) std::tie(first, last) = *options.samples;
    // Counted in pixel samples (unknown total for a time budget).
    Progress progress("render " + scene.modeName(),
                      timed ? 0 : static_cast<uint64_t>(width) * height * (last - first),
                      options.quiet);
    auto stopNow = [&] {
        if (stopped.load(std::memory_order_relaxed)) return true;
        if (!options.stopRequested || !options.stopRequested()) return false;
        stopped.store(true, std::memory_order_relaxed);
        return true;
    };

    // Samples [from, to) of every pixel; a tile not started once a stop is
    // asked for keeps what it had.
    auto pass = [&](int64_t from, int64_t to) {
        arena.execute([&] {
            tbb::parallel_for(
                tbb::blocked_range<int>(firstTile, endTile, 1),
                [&](const tbb::blocked_range<int>& r) {
                    PathCounters counters;
                    uint64_t dropped = 0;
                    // The batched integrator's paths: up to kBatchPaths
                    // (pixel, sample) pairs of a tile, in the per-path order.
                    std::vector<Rng> rngs;
                    std::vector<SampleStream> streams;
                    std::vector<PathQuery> queries;
                    std::vector<FirstHit> firstHits;
                    std::vector<std::pair<uint64_t, int64_t>> pixelSamples;
                    // One sample's result into the sums, in sample order per pixel.
                    auto accumulate = [&](uint64_t pixel, int64_t s, const Rgb& L,
                                          const FirstHit& hit) {
                        if (withAovs) {
                            double* p = &passSum[7 * pixel];
                            for (int c = 0; c < 3; ++c)
                                p[c] += hit.albedo[c], p[3 + c] += hit.normal[c];
                            p[6] += hit.hit ? hit.depth : 0.0;
                            if (s == 0) passId[pixel] = scene.passId(hit.geometry);
                        }
                        if (!L.isFinite()) {
                            ++dropped;
                            return;
                        }
                        double* acc = &sum[3 * pixel];
                        acc[0] += L.r, acc[1] += L.g, acc[2] += L.b;
                    };
                    // The camera ray of (pixel, s), from the sample's own stream.
                    auto cameraRay = [&](int x, int y, SampleStream& stream, Vec3* org, Vec3* dir) {
                        // y first: the order in which the renderer drew them
                        // before the stream (same images).
                        const std::array<double, 2> film = stream.get2D();
                        camera.ray(x + film[1], y + film[0], org, dir);
                    };
                    auto runBatch = [&] {
                        // firstHits is complete now: its addresses are stable.
                        for (size_t k = 0; k < queries.size(); ++k)
                            queries[k].first = withAovs ? &firstHits[k] : nullptr;
                        pathRadianceBatch(scene, queries, tracer, counters);
                        for (size_t k = 0; k < queries.size(); ++k)
                            accumulate(pixelSamples[k].first, pixelSamples[k].second,
                                       queries[k].radiance, firstHits[k]);
                        rngs.clear(), streams.clear(), queries.clear(), firstHits.clear(),
                            pixelSamples.clear();
                    };
                    for (int tile = r.begin(); tile < r.end(); ++tile) {
                        if (stopNow()) break;
                        const int x0 = (tile % tilesX) * kTile, y0 = (tile / tilesX) * kTile;
                        const int x1 = std::min(x0 + kTile, width),
                                  y1 = std::min(y0 + kTile, height);
                        for (int y = y0; y < y1; ++y) {
                            for (int x = x0; x < x1; ++x) {
                                const uint64_t pixel = static_cast<uint64_t>(y) * width + x;
                                for (int64_t s = from; s < to; ++s) {
                                    const uint64_t pixelKey =
                                        mixBits(options.seed ^ mixBits(pixel));
                                    if (batched) {
                                        // Streams refer to their Rng: reserved storage.
                                        if (rngs.empty()) {
                                            rngs.reserve(kBatchPaths);
                                            streams.reserve(kBatchPaths);
                                        }
                                        rngs.push_back(sampleRng(pixel, s, options.seed));
                                        streams.emplace_back(options.sampler, rngs.back(), pixelKey,
                                                             static_cast<uint32_t>(s));
                                        PathQuery q;
                                        cameraRay(x, y, streams.back(), &q.org, &q.dir);
                                        q.stream = &streams.back();
                                        queries.push_back(q);
                                        firstHits.emplace_back();
                                        pixelSamples.emplace_back(pixel, s);
                                        if (queries.size() == kBatchPaths) runBatch();
                                        continue;
                                    }
                                    Rng rng = sampleRng(pixel, s, options.seed);
                                    SampleStream stream(options.sampler, rng, pixelKey,
                                                        static_cast<uint32_t>(s));
                                    Vec3 org, dir;
                                    cameraRay(x, y, stream, &org, &dir);
                                    FirstHit hit;
                                    const Rgb L = pathRadiance(scene, org, dir, stream, tracer,
                                                               counters, withAovs ? &hit : nullptr);
                                    accumulate(pixel, s, L, hit);
                                }
                            }
                        }
                        if (!queries.empty()) runBatch();
                        tileSamples[static_cast<size_t>(tile)] = to - first;
                        progress.add(static_cast<uint64_t>(x1 - x0) * (y1 - y0) * (to - from));
                    }
                    rays.fetch_add(counters.rays, std::memory_order_relaxed);
                    paths.fetch_add(counters.paths, std::memory_order_relaxed);
                    truncated.fetch_add(counters.truncated, std::memory_order_relaxed);
                    nonFinite.fetch_add(dropped, std::memory_order_relaxed);
                });
        });
    };

    int passes = 0;
    // The samples pixel (x, y) has: its tile's.
    auto samplesAt = [&](int x, int y) {
        return tileSamples[static_cast<size_t>((y / kTile) * tilesX + x / kTile)];
    };
    auto result = [&](bool partial) {
        RenderResult r;
        r.image = Image(width, height);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const int64_t n = samplesAt(x, y);
                const double inv = n > 0 ? 1.0 / static_cast<double>(n) : 0.0;
                const size_t i = 3 * (static_cast<size_t>(y) * width + x);
                for (int c = 0; c < 3; ++c)
                    r.image.pixels[i + c] = static_cast<float>(sum[i + c] * inv);
            }
        for (const Aov aov : kAovs) {
            if (!(options.aovs & aov)) continue;
            Image pass(width, height);
            for (int y = 0; y < height; ++y)
                for (int x = 0; x < width; ++x) {
                    const int64_t n = samplesAt(x, y);
                    const double inv = n > 0 ? 1.0 / static_cast<double>(n) : 0.0;
                    const size_t pixel = static_cast<size_t>(y) * width + x;
                    const double* p = &passSum[7 * pixel];
                    Rgb v;
                    if (aov == kAovAlbedo) v = Rgb(p[0], p[1], p[2]) * inv;
                    if (aov == kAovNormal) v = Rgb(p[3], p[4], p[5]) * inv;
                    if (aov == kAovDepth) v = Rgb(p[6] * inv);
                    if (aov == kAovYarnId) v = Rgb(n > 0 ? passId[pixel] : 0);
                    pass.set(x, y, v);
                }
            r.aovs.emplace_back(aovName(aov), std::move(pass));
        }
        const auto [fewest, most] =
            std::minmax_element(tileSamples.begin() + firstTile, tileSamples.begin() + endTile);
        const double seconds = secondsSince(start);
        RenderStats& st = r.stats;
        st.mode = scene.modeName();
        st.width = width, st.height = height;
        st.spp = *fewest, st.sppMax = *most, st.passes = passes;
        st.partial = partial;
        st.sppRequested = timed ? 0 : last - first;
        st.seconds = seconds;
        st.secondsPerSpp = seconds / static_cast<double>(std::max<int64_t>(*most, 1));
        st.rays = rays.load();
        st.raysPerSecond = seconds > 0 ? static_cast<double>(st.rays) / seconds : 0;
        st.threads = threads;
        st.seed = options.seed;
        st.sampler = options.sampler;
        st.peakResidentBytes = peakResidentBytes();
        st.scene = scene.stats();
        st.nonFiniteSamples = static_cast<int64_t>(nonFinite.load());
        st.truncatedPaths = static_cast<int64_t>(truncated.load());
        st.truncatedFraction = paths.load() > 0 ? static_cast<double>(truncated.load()) /
                                                      static_cast<double>(paths.load())
                                                : 0.0;
        st.shard = options.shard;
        st.shardSpp = options.shard ? options.spp : 0;
        st.firstSample = first;
        if (options.shard) st.pixelChecksum = pixelChecksum(r.image);
        return r;
    };

    // Passes: 1 spp, then what the time per sample says takes about
    // max(kPassSeconds, elapsed / 4), at most the checkpoint interval, within
    // the budget.
    int64_t done = 0, next = 1;
    auto lastCheckpoint = start;
    while (true) {
        pass(first + done, first + done + next);
        if (stopped.load()) break;
        done += next, ++passes;
        const double elapsed = secondsSince(start);
        const double perSample = elapsed / static_cast<double>(done);
        if (timed) progress.setStatus(std::to_string(done) + " spp");
        double passSeconds = std::max(kPassSeconds, 0.25 * elapsed);
        if (options.checkpointSeconds > 0)
            passSeconds = std::min(passSeconds, options.checkpointSeconds);
        next = std::max<int64_t>(1, static_cast<int64_t>(std::floor(passSeconds / perSample)));
        if (timed) {
            next = std::min<int64_t>(
                {next, done,
                 static_cast<int64_t>(std::floor((options.seconds - elapsed) / perSample))});
            if (next < 1) break;
        } else {
            next = std::min(next, last - first - done);
            if (next < 1) break;
        }
        if (options.checkpoint && options.checkpointSeconds > 0 &&
            secondsSince(lastCheckpoint) >= options.checkpointSeconds) {
            options.checkpoint(result(true));
            lastCheckpoint = Clock::now();
        }
    }
    progress.finish();
    return result(stopped.load());
}

std::string truncationWarning(const RenderStats& stats, int maxDepth) {
    if (stats.truncatedFraction <= kTruncationWarningFraction) return "";
    char text[320];
    std::snprintf(text, sizeof text,
                  "%.2f %% of the paths reached render.max_depth = %d scattering events while "
                  "still carrying light and were cut: the image lacks their further light "
                  "(darker, not noisier); raise render.max_depth (at most 10000)",
                  100 * stats.truncatedFraction, maxDepth);
    return text;
}

nlohmann::json toJson(const RenderStats& s) {
    nlohmann::json j = {
        {"mode", s.mode},
        {"width", s.width},
        {"height", s.height},
        {"spp", s.spp},
        {"partial", s.partial},
        {"passes", s.passes},
        {"seconds", s.seconds},
        {"seconds_per_spp", s.secondsPerSpp},
        {"rays", s.rays},
        {"rays_per_second", s.raysPerSecond},
        {"threads", s.threads},
        {"seed", s.seed},
        {"sampler", samplerKindName(s.sampler)},
        {"peak_resident_bytes", s.peakResidentBytes},
        {"non_finite_samples", s.nonFiniteSamples},
        {"truncated_paths", s.truncatedPaths},
        {"truncated_fraction", s.truncatedFraction},
        {"scene",
         {{"curves", s.scene.curves},
          {"curve_points", s.scene.curvePoints},
          {"tubes", s.scene.tubes},
          {"segments", s.scene.segments},
          {"objects", s.scene.objects},
          {"triangles", s.scene.triangles},
          {"geometry_bvh_bytes", s.scene.embreeBytes},
          {"geometry_bvh_peak_bytes", s.scene.embreePeakBytes},
          {"materials", s.scene.materials},
          {"material_bytes", s.scene.materialBytes},
          {"build_seconds", s.scene.seconds}}},
        {"yarn_overlap", yarnOverlapJson(s.scene.yarnOverlap)},
        {"appearance", appearanceJson(s.scene)},
    };
    if (s.partial) {
        j["spp_requested"] = s.sppRequested;
        j["spp_max"] = s.sppMax;
    }
    if (s.shard)
        j["shard"] = {{"index", s.shard->index},
                      {"count", s.shard->count},
                      {"spp", s.shardSpp},
                      {"first_sample", s.firstSample},
                      {"end_sample", s.firstSample + s.spp},
                      {"checksum", s.pixelChecksum}};
    return j;
}

}  // namespace weft::render
