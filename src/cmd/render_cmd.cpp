// weft render: a cloth scene to an image, its yarns in neural, fiber or dual mode (docs/render.md).
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "commands.h"
#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/image.h"
#include "weft/core/image_io.h"
#include "weft/core/json_message.h"
#include "weft/core/text_parse.h"
#include "weft/render/render_merge.h"
#include "weft/render/renderer.h"
#include "weft/render/scene.h"
#include "weft/render/scene_file.h"

namespace weft::cmd {

namespace {

struct RenderCmdOptions {
    std::string scene, mode, out, yarnSampling = "tabulated", shard, sampler, integrator = "auto";
    int spp = 0, threads = 0;
    double seconds = 0, checkpoint = 0;
    std::string exposure = "0", aovs, frames, frameShard;
    double turntable = 0;
    CLI::Option* turntableOpt = nullptr;
    uint64_t seed = 0, fiberSeed = 0;
    CLI::Option* fiberSeedOpt = nullptr;
    CLI::Option *sppOpt = nullptr, *timeOpt = nullptr, *seedOpt = nullptr, *shardOpt = nullptr,
                *samplerOpt = nullptr;
    bool noNee = false, quiet = false;
};

// IMAGE.exr -> IMAGE (the stem the PNG and JSON share).
std::string outputStem(const std::string& out) {
    const std::string json = render::renderStatsPath(out, "--out " + out);
    return json.substr(0, json.size() - 5);
}

// A render's outputs: IMAGE.exr, IMAGE.png and the statistics, IMAGE.json, or
// IMAGE.render.json where IMAGE.json is the scene file (`weft render
// knit.json --out knit.exr`; docs/render.md); and IMAGE.<pass>.exr for each
// render pass (--aov).
struct RenderOutputs {
    std::string exr, png, json;
    std::vector<std::pair<std::string, std::string>> passes;  // (name, IMAGE.<name>.exr)

    RenderOutputs(const std::string& out, const std::string& sceneFile, unsigned aovs = 0)
        : exr(out), png(outputStem(out) + ".png"), json(outputStem(out) + ".json") {
        if (sameFilePath(json, sceneFile))
            json = render::renamedRenderStatsPath(out, "--out " + out);
        for (const render::Aov aov : render::kAovs)
            if (aovs & aov)
                passes.emplace_back(render::aovName(aov),
                                    outputStem(out) + "." + render::aovName(aov) + ".exr");
    }
    std::vector<CommandPath> paths() const {
        std::vector<CommandPath> p = {
            {"--out", exr}, {"--out's PNG", png}, {"--out's statistics", json}};
        for (const auto& [name, path] : passes) p.push_back({"--aov " + name, path});
        return p;
    }
};

// "auto" (nullopt) or stops in [-64, 64]; InputError naming the flag otherwise.
std::optional<double> parseExposure(const std::string& text, const std::string& flag) {
    if (text == "auto") return std::nullopt;
    double stops = 0;
    if (!parseNumber(std::string_view(text), &stops))
        throw InputError(flag + " \"" + text +
                         "\": expected stops (a number in [-64, 64]) or auto");
    checkExposureStops(stops, flag);
    return stops;
}

// The outputs, all or none (each through a temporary file renamed into place).
void writeRenderFiles(const RenderOutputs& out, const Image& image,
                      const std::vector<std::pair<std::string, Image>>& passes,
                      nlohmann::json& stats, std::optional<double> exposure) {
    const double stops = exposure ? *exposure : autoExposure(image);
    stats["exposure"] = stops;
    if (!exposure) stats["exposure_auto"] = true;
    stats["outputs"] = {{"exr", out.exr}, {"png", out.png}, {"json", out.json}};
    std::vector<std::pair<std::string, std::string>> files = {{out.exr, encodeExr(image, out.exr)},
                                                              {out.png, encodePng(image, stops)}};
    for (size_t k = 0; k < out.passes.size() && k < passes.size(); ++k) {
        stats["outputs"][out.passes[k].first] = out.passes[k].second;
        files.push_back({out.passes[k].second, encodeExr(passes[k].second, out.passes[k].second)});
    }
    files.push_back({out.json, stats.dump(2) + "\n"});
    writeFilesAtomic(files);
}

// writeRenderFiles, then the one-line summary.
void writeRenderOutputs(const RenderOutputs& out, const Image& image,
                        const std::vector<std::pair<std::string, Image>>& passes,
                        nlohmann::json stats, std::optional<double> exposure) {
    writeRenderFiles(out, image, passes, stats, exposure);
    nlohmann::json line = {{"exr", out.exr},         {"png", out.png},
                           {"json", out.json},       {"mode", stats.at("mode")},
                           {"spp", stats.at("spp")}, {"seconds", stats.at("seconds")}};
    if (stats.value("partial", false)) line["partial"] = true;
    std::printf("%s\n", line.dump().c_str());
}

// What every frame of one `weft render` shares.
struct RenderSetup {
    unsigned aovs = 0;
    std::optional<double> exposure;
    render::SceneOptions sceneOptions;
};

// The spp a render of `desc` asks for: --spp, else the scene's; 0 for --time.
int requestedSpp(const RenderCmdOptions& o, const render::SceneDesc& desc) {
    return o.sppOpt->count() ? o.spp : (o.timeOpt->count() ? 0 : desc.render.spp);
}

// Renders `desc` to `outputs` (the whole of a plain render, one frame of an
// animation); a render stopped by a signal writes what it has and throws
// ExitStatus. `knownHash`: the scene's sceneHash when the caller has it (a
// frame's resume check), else computed here. `frame`: the frame number for
// the statistics, or none.
void renderOne(const RenderCmdOptions& o, const RenderSetup& setup, const render::SceneDesc& desc,
               const std::optional<std::string>& knownHash, const RenderOutputs& outputs,
               std::optional<int> frame) {
    checkOutputsSpareInputs(render::sceneInputs(desc, o.scene), outputs.paths());
    // Before the scene is built and rendered: a bad destination fails now.
    checkOutputsWritable(outputs.paths());

    render::RenderOptions options;
    // Flags override the scene's spp; RenderOptions::validate checks that
    // exactly one budget is left and its range.
    options.spp = requestedSpp(o, desc);
    options.seconds = o.timeOpt->count() ? o.seconds : 0;
    options.threads = o.threads;
    options.seed = o.seedOpt->count() ? o.seed : desc.render.seed;
    options.maxDepth = desc.render.maxDepth;
    options.sampler = desc.render.sampler;
    if (o.samplerOpt->count()) options.sampler = render::parseSampler(o.sampler);
    options.nextEventEstimation = !o.noNee;
    options.integrator = render::parsePathIntegrator(o.integrator, "--integrator");
    options.quiet = o.quiet;
    if (o.shardOpt->count()) options.shard = Shard::parse(o.shard, "--shard");
    options.checkpointSeconds = o.checkpoint;
    options.aovs = setup.aovs;
    options.validate();

    const std::string hash = knownHash ? *knownHash : render::sceneHash(desc);
    const render::Scene scene(desc, setup.sceneOptions);
    if (!o.quiet)
        for (const std::string& w :
             render::yarnOverlapWarnings(desc.path, scene.stats().yarnOverlap))
            std::fprintf(stderr, "weft: warning: %s\n", w.c_str());
    if (!o.quiet)
        for (const std::string& n : render::appearanceNotes(desc.path, scene.stats()))
            std::fprintf(stderr, "weft: %s\n", n.c_str());
    auto statsOf = [&](const render::RenderStats& st) {
        nlohmann::json stats = render::toJson(st);
        stats["scene_file"] = o.scene;
        stats["scene_hash"] = hash;
        stats["next_event_estimation"] = !o.noNee;
        stats["yarn_sampling"] = yarnSamplingName(setup.sceneOptions.yarn.sampling);
        stats["max_depth"] = options.maxDepth;
        stats["version"] = WEFT_VERSION;
        if (frame) stats["frame"] = *frame;
        return stats;
    };
    // The image so far, every --checkpoint seconds (partial: true in its statistics).
    options.checkpoint = [&](const render::RenderResult& partial) {
        nlohmann::json stats = statsOf(partial.stats);
        writeRenderFiles(outputs, partial.image, partial.aovs, stats, setup.exposure);
    };
    // The first SIGINT or SIGTERM: the tiles in flight finish, the image so far is written.
    const StopOnSignal stop("the image of the samples traced so far");
    options.stopRequested = [] { return StopOnSignal::signal() != 0; };
    const render::RenderResult result = render::render(scene, options);

    if (const std::string w = render::truncationWarning(result.stats, options.maxDepth); !w.empty())
        std::fprintf(stderr, "weft: warning: %s\n", w.c_str());
    if (result.stats.nonFiniteSamples > 0)
        std::fprintf(stderr, "weft: warning: %lld samples were NaN or infinite and were dropped\n",
                     static_cast<long long>(result.stats.nonFiniteSamples));
    writeRenderOutputs(outputs, result.image, result.aovs, statsOf(result.stats), setup.exposure);
    if (result.stats.partial) {
        const int signal = StopOnSignal::signal();
        std::fprintf(
            stderr,
            "weft: stopped by %s after %lld samples per pixel (up to %lld) of %s: %s "
            "holds them (\"partial\": true in %s)\n",
            signal == SIGTERM ? "SIGTERM" : "SIGINT", static_cast<long long>(result.stats.spp),
            static_cast<long long>(result.stats.sppMax),
            result.stats.sppRequested > 0 ? std::to_string(result.stats.sppRequested).c_str()
                                          : "the time budget",
            outputs.exr.c_str(), outputs.json.c_str());
        throw ExitStatus{128 + (signal != 0 ? signal : SIGINT)};
    }
}

// "A:B" (A <= B, both in [0, kMaxFrame]); InputError naming --frames otherwise.
std::pair<int, int> parseFrames(const std::string& text) {
    const size_t colon = text.find(':');
    int a = 0, b = 0;
    if (colon == std::string::npos || !parseNumber(std::string_view(text).substr(0, colon), &a) ||
        !parseNumber(std::string_view(text).substr(colon + 1), &b) || a < 0 || b < a ||
        b > render::kMaxFrame)
        throw InputError("--frames \"" + text + "\": expected FIRST:LAST, 0 <= FIRST <= LAST <= " +
                         std::to_string(render::kMaxFrame));
    return {a, b};
}

// A frame finished earlier: its statistics say complete, of this frame's scene
// (hash) and of the samples asked for.
bool finishedEarlier(const RenderOutputs& outputs, const std::string& hash, int spp) {
    std::error_code ec;
    if (!std::filesystem::exists(outputs.exr, ec) || !std::filesystem::exists(outputs.json, ec))
        return false;
    try {
        const nlohmann::json stats = nlohmann::json::parse(readFile(outputs.json));
        return !stats.value("partial", true) && stats.value("scene_hash", "") == hash &&
               (spp == 0 || stats.value("spp", 0) == spp);
    } catch (const std::exception&) {
        return false;
    }
}

void runRender(const RenderCmdOptions& o) {
    // Not CLI11-required: `weft render merge` does without them.
    if (o.scene.empty() || o.out.empty())
        throw InputError(
            "weft render needs SCENE and --out IMAGE.exr (or: weft render merge "
            "PART.exr... --out IMAGE.exr)");
    RenderSetup setup;
    setup.aovs = o.aovs.empty() ? 0 : render::parseAovs(o.aovs);
    setup.exposure = parseExposure(o.exposure, "--exposure");
    if (!o.mode.empty()) setup.sceneOptions.mode = render::yarnModeNamed(o.mode).name();
    setup.sceneOptions.quiet = o.quiet;
    setup.sceneOptions.yarn.sampling = parseYarnSampling(o.yarnSampling, "--yarn-sampling");
    render::SceneDesc desc = render::loadScene(o.scene);
    // Part of the scene (its hash, the statistics' scene), not a render option.
    if (o.fiberSeedOpt->count()) desc.render.fiberSeed = o.fiberSeed;
    if (!o.frames.empty()) {
        const auto [a, b] = parseFrames(o.frames);
        desc.animation.first = a, desc.animation.last = b;
    }
    if (o.turntableOpt->count()) {
        if (!std::isfinite(o.turntable) || std::abs(o.turntable) > 3600)
            throw InputError("--turntable " + formatNumber(o.turntable) +
                             " is out of range: allowed [-3600, 3600] degrees");
        desc.animation.turntableDeg = o.turntable;
    }
    const bool animated =
        render::isAnimated(desc) || desc.animation.hasRange() || desc.animation.turntableDeg != 0;
    if (!animated) {
        if (!o.frameShard.empty())
            throw InputError("--frame-shard applies to an animation (--frames)");
        renderOne(o, setup, desc, std::nullopt, RenderOutputs(o.out, o.scene, setup.aovs),
                  std::nullopt);
        return;
    }
    if (!desc.animation.hasRange())
        throw InputError(o.scene +
                         ": an animation (a frame pattern in a file name, or a "
                         "turntable) needs its frames: \"animation\": {\"frames\": [FIRST, LAST]} "
                         "or --frames FIRST:LAST");
    if (o.shardOpt->count())
        throw InputError(
            "--shard splits one image's samples; an animation splits its frames: "
            "--frame-shard K/N");
    // Every frame by default: shard 0 of 1.
    const Shard frameShard =
        o.frameShard.empty() ? Shard{0, 1} : Shard::parse(o.frameShard, "--frame-shard");
    // IMAGE.%04d.exr unless --out names its own pattern.
    std::string pattern = o.out;
    if (!render::hasFramePattern(pattern)) {
        const std::string stem = outputStem(o.out);
        pattern = stem + ".%04d" + o.out.substr(stem.size());
    }
    render::frameFileName(pattern, 0, "--out");
    const int first = desc.animation.first, last = desc.animation.last;
    for (int f = first; f <= last; ++f) {
        if ((f - first) % frameShard.count != frameShard.index) continue;
        const render::SceneDesc frameDesc = render::sceneAtFrame(desc, f, first, last);
        const RenderOutputs outputs(render::frameFileName(pattern, f, "--out"), o.scene,
                                    setup.aovs);
        // Hashed once: the resume check and the frame's statistics.
        const std::string hash = render::sceneHash(frameDesc);
        if (finishedEarlier(outputs, hash, requestedSpp(o, desc))) {
            std::printf("%s\n", nlohmann::json({{"frame", f}, {"exr", outputs.exr}, {"kept", true}})
                                    .dump()
                                    .c_str());
            continue;
        }
        renderOne(o, setup, frameDesc, hash, outputs, f);
    }
}

struct RenderMergeOptions {
    std::vector<std::string> parts;
    std::string out, exposure = "0";
};

void runRenderMerge(const RenderMergeOptions& o) {
    const RenderOutputs outputs(o.out, "");
    const std::optional<double> exposure = parseExposure(o.exposure, "--exposure");
    std::vector<CommandPath> inputs;
    for (const std::string& part : o.parts) {
        inputs.push_back({"part", part});
        inputs.push_back({"part's statistics", render::renderStatsPath(part, "part " + part)});
    }
    checkOutputsSpareInputs(inputs, outputs.paths());
    const render::MergedRender merged = render::mergeRenderParts(o.parts);
    writeRenderOutputs(outputs, merged.image, {}, merged.stats, exposure);
}

}  // namespace

void addRenderCommand(CLI::App& app) {
    auto o = std::make_shared<RenderCmdOptions>();
    CLI::App* cmd = app.add_subcommand(
        "render",
        "Render a cloth scene (docs/render.md, docs/scene-format.md) to IMAGE.exr, "
        "IMAGE.png and IMAGE.json (statistics).");
    cmd->add_option("scene", o->scene, "Scene file (JSON; required)");
    cmd->add_option("--mode", o->mode,
                    "Draw every yarn this way, over the yarns' own \"mode\" (default: each "
                    "yarn's, neural where it names none). neural: plies as curves with the yarn "
                    "BSDF; fiber: every fiber drawn (ground truth); dual: plies as curves with the "
                    "dual-scattering baseline (after ZMA23, docs/dual-scattering.md), from the "
                    "model's fiber and ply");
    cmd->add_option("--yarn-sampling", o->yarnSampling,
                    "Neural mode: how the yarn BSDF samples directions: tabulated (in "
                    "proportion to the model, from tables built at load), fitted (the paper's "
                    "lobe selection and M lobe) or cosine (cosine about the normal on either side, "
                    "for the sampling ablation; the T lobe stays a delta)")
        ->capture_default_str();
    o->sppOpt =
        cmd->add_option("--spp", o->spp, "Samples per pixel (default: the scene's render.spp)");
    o->timeOpt = cmd->add_option(
        "--time", o->seconds, "Render progressive passes for this many seconds instead of --spp");
    cmd->add_option("--threads", o->threads, "Worker threads (0: all cores)")
        ->capture_default_str();
    o->seedOpt =
        cmd->add_option("--seed", o->seed,
                        "Random seed, integer >= 0 (default: the scene's render.seed)")
            ->check(seedValidator());
    o->fiberSeedOpt =
        cmd->add_option("--fiber-seed", o->fiberSeed,
                        "Arrangement of the fibers in each ply in fiber mode, integer >= 0 "
                        "(default: the scene's render.fiber_seed, else 0; --seed does not move "
                        "the fibers)")
            ->check(seedValidator());
    o->samplerOpt = cmd->add_option(
        "--sampler", o->sampler,
        "independent (random numbers) or sobol (Owen-scrambled Sobol' points: each pixel's "
        "samples stratified, less noise at the same spp; docs/render.md). Default: the scene's "
        "render.sampler, else independent");
    cmd->add_option("--exposure", o->exposure,
                    "PNG exposure in stops, [-64, 64], or auto (the 99th percentile of the "
                    "luminance to 0.9: about 1 % of the pixels clip); the EXR stays linear")
        ->capture_default_str();
    cmd->add_option(
        "--aov", o->aovs,
        "Render passes, comma-separated: albedo, normal, depth, yarn_id, each written "
        "to IMAGE.<pass>.exr (first-hit values averaged over the pixel's samples; for "
        "denoisers and compositing, docs/render.md \"Render passes\"); not with --shard");
    cmd->add_option("--checkpoint", o->checkpoint,
                    "Write the image so far (EXR, PNG and statistics with \"partial\": true) "
                    "every SECONDS while rendering, in [0.1, 1e6] (docs/render.md, \"Keeping the "
                    "work\"); Ctrl-C or SIGTERM writes it without this flag too");
    cmd->add_option("--integrator", o->integrator,
                    "batch (paths of a tile advance together, the BSDF's networks run many "
                    "queries at once), path (one path at a time, the reference) or auto "
                    "(batch in neural mode, where it is faster); the same image bit for bit "
                    "(docs/render.md, \"Batched shading\")")
        ->capture_default_str();
    cmd->add_flag("--no-nee", o->noNee,
                  "Turn off next-event estimation (BSDF sampling only; for checking estimators)");
    cmd->add_flag("--quiet", o->quiet,
                  "No progress output and no warning about yarns that overlap (the statistics "
                  "still record yarn_overlap)");
    cmd->add_option("--frames", o->frames,
                    "FIRST:LAST: render these frames of an animation (file names with a frame "
                    "pattern such as knit.%04d.bcc, docs/render.md \"Animation\"), over the "
                    "scene's animation.frames; outputs IMAGE.%04d.exr (or --out's own pattern); "
                    "frames finished earlier are kept");
    cmd->add_option("--frame-shard", o->frameShard,
                    "K/N: render only frames FIRST + K, FIRST + K + N, ... (a Slurm array task "
                    "each, docs/cluster.md)");
    o->turntableOpt = cmd->add_option(
        "--turntable", o->turntable,
        "DEGREES: turn the camera about +y through camera.to by this much over the frames "
        "(an animation: needs --frames), [-3600, 3600]");
    o->shardOpt = cmd->add_option(
        "--shard", o->shard,
        "K/N: trace only shard K (0..N-1) of N of the --spp samples, [K spp/N, (K+1) spp/N) of "
        "every pixel, for weft render merge (docs/cluster.md)");
    cmd->add_option("--out", o->out,
                    "Output IMAGE.exr (IMAGE.png and IMAGE.json beside it; required)");

    auto mo = std::make_shared<RenderMergeOptions>();
    CLI::App* merge = cmd->add_subcommand(
        "merge", "The sample-weighted mean of the parts written by weft render --shard K/N "
                 "(docs/cluster.md): IMAGE.exr, IMAGE.png and IMAGE.json");
    merge->add_option("parts", mo->parts,
                      "the N parts PART.exr (each with PART.json beside it), in any order")
        ->required();
    merge
        ->add_option("--exposure", mo->exposure,
                     "PNG exposure in stops, [-64, 64], or auto (the EXR stays linear)")
        ->capture_default_str();
    merge->add_option("--out", mo->out, "Output IMAGE.exr (IMAGE.png and IMAGE.json beside it)")
        ->required();
    merge->callback([mo] { runRenderMerge(*mo); });
    cmd->require_subcommand(0, 1);
    cmd->callback([o, merge] {
        if (!merge->parsed()) runRender(*o);
    });
}

}  // namespace weft::cmd
