// weft montage: renders and heatmaps side by side in one PNG (docs/compare.md).
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "commands.h"
#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/image.h"
#include "weft/core/image_io.h"
#include "weft/eval/image_montage.h"

namespace weft::cmd {

namespace {

struct MontageCmdOptions {
    std::vector<std::string> inputs;
    std::string out;
    eval::MontageOptions montage;
};

void runMontage(const MontageCmdOptions& o) {
    o.montage.validate();
    if (lowercaseExtension(o.out) != ".png")
        throw InputError("--out " + o.out + ": expected a .png file");
    std::vector<CommandPath> inputs;
    for (size_t k = 0; k < o.inputs.size(); ++k)
        inputs.push_back({"input image " + std::to_string(k + 1), o.inputs[k]});
    checkOutputsSpareInputs(inputs, {{"--out", o.out}});
    std::vector<Image> images;
    std::vector<bool> linear;
    for (const std::string& path : o.inputs) {
        images.push_back(readImageOrPng(path));
        linear.push_back(lowercaseExtension(path) != ".png");
    }
    const Image figure = eval::montage(images, linear, o.montage);
    writePng(o.out, figure);
    const nlohmann::json line = {{"out", o.out},
                                 {"width", figure.width},
                                 {"height", figure.height},
                                 {"images", images.size()}};
    std::printf("%s\n", line.dump().c_str());
}

}  // namespace

void addMontageCommand(CLI::App& app) {
    auto o = std::make_shared<MontageCmdOptions>();
    CLI::App* cmd = app.add_subcommand(
        "montage",
        "Place images side by side in one PNG figure (renders as .exr/.hdr, tone-mapped with "
        "--exposure; heatmaps and other .png files as they are), left to right in rows");
    cmd->add_option("images", o->inputs, "Input images (.exr, .hdr or .png), at most 64")
        ->required();
    cmd->add_option("--out", o->out, "Output figure (.png, written atomically)")->required();
    cmd->add_option("--columns", o->montage.columns, "Images per row (0: all in one row), [0, 64]")
        ->capture_default_str();
    cmd->add_option("--gap", o->montage.gap, "White pixels between and around images, [0, 256]")
        ->capture_default_str();
    cmd->add_option("--exposure", o->montage.exposure,
                    "Stops applied to .exr/.hdr inputs before the sRGB encoding, [-64, 64]")
        ->capture_default_str();
    cmd->callback([o] { runMontage(*o); });
}

}  // namespace weft::cmd
