// weft/render/renderer.h — the image loop of `weft render` (issue 7, docs/design.md 8).
//
// render() traces `spp` paths per pixel (pathRadiance, path_tracer.h) at
// uniformly random film positions inside the pixel (a box filter) and
// averages them. Their numbers come from the sampler of RenderOptions
// (core/sample_stream.h): independent, or Owen-scrambled Sobol' points that
// stratify each pixel's samples. Budgets: a fixed number of samples per
// pixel, or a time budget; either way the samples are traced in passes (1
// sample per pixel, then as many as the measured time per sample says take
// about max(kPassSeconds, a quarter of the time so far), at most the
// checkpoint interval, within the budget): for the time budget until the
// time is spent, at least one pass.
//
// Keeping the work (issue 43): between passes, a checkpoint callback receives
// the image so far (RenderStats::partial) every `checkpointSeconds`; when
// stopRequested() turns true (weft render: the first SIGINT or SIGTERM), the
// tiles being traced finish, no other tile starts, and render() returns what
// it has, partial, its pixels each the mean of the samples their tile
// reached (the tiles of the last pass that finished it have more: spp is the
// fewest, sppMax the most).
//
// Determinism: sample s of pixel p draws from Rng(stream p, seed mixed with
// s) and, with the sobol sampler, from Sobol' point s of that pixel, so the
// image depends only on (scene, mode, seed, sampler, spp), not on the number
// of threads or on how samples were split into passes, or into shards: shard
// K of N (RenderOptions::shard, core/shard.h) traces samples
// [floor(K spp / N), floor((K + 1) spp / N)) of every pixel, and the
// sample-weighted mean of the N images (render_merge.h) is the unsharded
// image up to float rounding. Tiles of 16 x 16 pixels are scheduled with TBB
// (an arena of `threads` workers).
#pragma once

#include <cstdint>
#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "weft/core/image.h"
#include "weft/core/shard.h"
#include "weft/render/path_tracer.h"
#include "weft/render/scene.h"

namespace weft::render {

struct RenderResult;

// Render passes (issue 43, docs/render.md "Render passes"): what each
// camera ray met first, averaged over the pixel's samples (yarn_id: its first
// sample's). albedo: the first BSDF sample's weight (an unbiased estimate of
// the BSDF's albedo there; 0 where the ray escapes); normal: the world
// shading normal turned towards the camera (0 where it escapes); depth: the
// distance to the first hit (0 where it escapes); yarn_id: the yarn entry i
// as i + 1, object j as -(j + 1), 0 for the sky or a light.
enum Aov : unsigned { kAovAlbedo = 1, kAovNormal = 2, kAovDepth = 4, kAovYarnId = 8 };
inline constexpr Aov kAovs[] = {kAovAlbedo, kAovNormal, kAovDepth, kAovYarnId};
const char* aovName(Aov aov);  // "albedo", "normal", "depth", "yarn_id"
// "albedo,normal" -> a mask; InputError naming --aov and the allowed names otherwise.
unsigned parseAovs(const std::string& list);

// How the renderer advances its paths: one at a time (pathRadiance, the
// reference), or up to kBatchPaths of a tile together, one scattering event
// at a time, with each event's BSDF calls batched (pathRadianceBatch: the
// same image bit for bit; docs/render.md "Batched shading"). Auto: batched
// where a material's BSDF batches faster (Scene::batchesFaster: neural
// mode), one at a time otherwise (fiber and dual mode, where batching
// measured slower).
enum class PathIntegrator { Auto, PerPath, Batched };
inline constexpr size_t kBatchPaths = 256;
const char* pathIntegratorName(PathIntegrator integrator);  // "auto", "path", "batch"
// "auto", "path" or "batch"; InputError naming `what` and the allowed values otherwise.
PathIntegrator parsePathIntegrator(const std::string& name, const std::string& what);

struct RenderOptions {
    int spp = 0;         // > 0: this many samples per pixel
    double seconds = 0;  // > 0 (and spp == 0): progressive passes for this long
    int threads = 0;     // 0: all cores
    uint64_t seed = 0;
    SamplerKind sampler = SamplerKind::Independent;  // core/sample_stream.h
    int maxDepth = 1000;  // path_tracer.h: fewer cuts near-white fiber paths
    bool nextEventEstimation = true;
    PathIntegrator integrator = PathIntegrator::Auto;
    bool quiet = false;  // no progress output
    // A part of an spp render for `weft render merge`: only this shard's samples.
    std::optional<Shard> shard;
    // Asked between tiles; true: stop early and return the partial image.
    std::function<bool()> stopRequested;
    // > 0: `checkpoint` receives the image so far after the first pass that
    // ends this many seconds after the last checkpoint (or the start).
    double checkpointSeconds = 0;
    std::function<void(const RenderResult&)> checkpoint;
    unsigned aovs = 0;  // Aov bits: the passes to compute (not with a shard)
    // Only samples [first, end) of every pixel (weft view's progressive
    // passes, issue 44): the image is their mean, so the sample-weighted mean
    // of consecutive ranges is the image of an spp render, as for shards.
    // Needs 0 <= first < end <= spp; not with a shard.
    std::optional<std::pair<int64_t, int64_t>> samples;
    // Only pixel rows [first, end) (weft view's bands of a slow sample): the
    // tiles of those rows; the other pixels are 0 and the statistics count
    // the band's tiles. first a multiple of kRenderTile, end <= the height.
    std::optional<std::pair<int, int>> rows;

    // InputError naming the flag and its range (exactly one budget, threads
    // in [0, 1024], maxDepth in [1, 10000]; a shard needs spp and N <= spp;
    // checkpointSeconds 0 or in [0.1, 1e6]).
    void validate() const;
};

struct RenderStats {
    std::string mode;
    int width = 0, height = 0;
    int64_t spp = 0;  // samples per pixel traced (by this shard, for a part)
    int passes = 0;
    // Stopped early (stopRequested) or a checkpoint: fewer samples than asked
    // for, sppRequested (0 for a time budget); sppMax, the most any pixel got.
    bool partial = false;
    int64_t sppRequested = 0, sppMax = 0;
    double seconds = 0;  // rendering, without the scene build
    double secondsPerSpp = 0;
    uint64_t rays = 0;  // closest-hit and shadow queries
    double raysPerSecond = 0;
    int threads = 0;
    uint64_t seed = 0;
    SamplerKind sampler = SamplerKind::Independent;
    int64_t peakResidentBytes = 0;  // of the whole process (getrusage)
    SceneBuildStats scene;
    int64_t nonFiniteSamples = 0;  // samples dropped as NaN/Inf (reported; should stay 0)
    // Paths cut at maxDepth while still carrying light, and their share of all
    // paths: the image lacks their further light (a bias, not noise).
    int64_t truncatedPaths = 0;
    double truncatedFraction = 0;
    // A part: its shard of `shardSpp` samples per pixel, samples [firstSample, firstSample + spp),
    // and pixelChecksum (core/image.h) of its image, which the merge verifies.
    std::optional<Shard> shard;
    int64_t shardSpp = 0, firstSample = 0;
    std::string pixelChecksum;
};

struct RenderResult {
    Image image;  // linear RGB, the mean of the samples
    RenderStats stats;
    // The passes asked for, in kAovs order: (name, image; depth and yarn_id
    // in all three channels).
    std::vector<std::pair<std::string, Image>> aovs;
};

RenderResult render(const Scene& scene, const RenderOptions& options);

// The side of the square tiles the renderer schedules (pixels).
constexpr int kRenderTile = 16;

// The shortest pass the renderer plans (seconds): longer passes lose less to
// the tiles that finish last.
constexpr double kPassSeconds = 2.0;

// Paths cut at max_depth above this share bias the image visibly (a darker
// cloth): weft render warns.
constexpr double kTruncationWarningFraction = 1e-3;
// The warning for a render whose truncatedFraction exceeds kTruncationWarningFraction
// (what was cut, and the fix), or "" below it.
std::string truncationWarning(const RenderStats& stats, int maxDepth);

// "independent" or "sobol"; InputError naming `field` and the allowed names otherwise.
SamplerKind parseSampler(const std::string& name, const std::string& field = "--sampler");

// Peak resident set size of this process in bytes.
int64_t peakResidentBytes();

nlohmann::json toJson(const RenderStats& stats);

}  // namespace weft::render
