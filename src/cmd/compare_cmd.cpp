// weft compare: SSIM, RMSE and relative MSE of an image against a reference,
// with an optional SSIM heatmap (docs/compare.md).
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "commands.h"
#include "weft/core/file.h"
#include "weft/core/image.h"
#include "weft/eval/image_compare.h"

namespace weft::cmd {

namespace {

struct CompareCmdOptions {
    std::string a, b, heatmap, json;
    bool perChannel = false;
    double exposure = 0;
    int scale = 1;
};

void runCompare(const CompareCmdOptions& o) {
    eval::CompareOptions options;
    options.mode = o.perChannel ? eval::SsimMode::PerChannel : eval::SsimMode::Luminance;
    options.exposure = o.exposure;
    options.scale = o.scale;
    checkOutputsSpareInputs({{"image A", o.a}, {"image B", o.b}},
                            {{"--heatmap", o.heatmap}, {"--json", o.json}});
    const eval::ImageComparison c = eval::compareImageFiles(o.a, o.b, options);
    const std::string line = eval::toJson(c).dump();
    std::vector<std::pair<std::string, std::string>> files;
    if (!o.heatmap.empty()) files.emplace_back(o.heatmap, encodePng(eval::ssimHeatmap(c)));
    if (!o.json.empty()) files.emplace_back(o.json, line + "\n");
    writeFilesAtomic(files);
    std::printf("%s\n", line.c_str());
}

}  // namespace

void addCompareCommand(CLI::App& app) {
    auto o = std::make_shared<CompareCmdOptions>();
    CLI::App* cmd = app.add_subcommand(
        "compare",
        "Compare image A against the reference B (.exr or .hdr, linear RGB; or .png; same "
        "size): SSIM on the tone-mapped image, RMSE and relative MSE (docs/compare.md). Prints "
        "one JSON line.");
    cmd->add_option("a", o->a, "The image to score (.exr or .hdr; .png is decoded from sRGB)")
        ->required();
    cmd->add_option("b", o->b, "The reference image (.exr or .hdr; .png is decoded from sRGB)")
        ->required();
    cmd->add_option("--heatmap", o->heatmap,
                    "Write the per-pixel SSIM map as a PNG: 1 - SSIM in viridis, 0 (dark "
                    "purple) to 1 (yellow)");
    cmd->add_option("--json", o->json, "Also write the JSON line to this file");
    cmd->add_flag("--per-channel", o->perChannel,
                  "SSIM on each sRGB channel, averaged (default: on the luminance)");
    cmd->add_option("--exposure", o->exposure,
                    "Stops applied to both images before SSIM's tone map, in [-64, 64] (RMSE "
                    "and relative MSE stay linear)")
        ->capture_default_str();
    cmd->add_option("--scale", o->scale,
                    "Average both images over K x K pixel blocks before every metric, in [1, "
                    "64]: compares structure larger than K pixels (a ply-level model against "
                    "the fibers at the scale of the ply)")
        ->capture_default_str();
    cmd->callback([o] { runCompare(*o); });
}

}  // namespace weft::cmd
