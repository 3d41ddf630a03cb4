// weft yarn eval | sample | check | appearance: probes of the aggregated yarn BSDF
// (docs/yarn.md, docs/colour.md).
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "commands.h"
#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/image.h"
#include "weft/core/json_file.h"
#include "weft/core/json_message.h"
#include "weft/core/npy.h"
#include "weft/core/text_parse.h"
#include "weft/fit/fit.h"
#include "weft/fit/model_check.h"
#include "weft/gather/rdm_io.h"
#include "weft/yarn/family_model.h"
#include "weft/yarn/material_preset.h"
#include "weft/yarn/yarn_appearance.h"
#include "weft/yarn/yarn_bsdf.h"

namespace weft::cmd {

namespace {

struct EvalOptions {
    std::string model, in, out;
    bool noGuard = false;
};

struct SampleOptions {
    std::string model, wi, out;
    int64_t count = 0;
    uint64_t seed = 0;
    bool noGuard = false;
};

struct CheckOptions {
    std::string model, rdm, out, cTT;
    int64_t minPaths = 1000;
    int threads = 0;
    bool dual = false;
};

struct AppearanceOptions {
    std::string model, appearance, cTT;
};

// One JSON line: appearanceReport (yarn_appearance.h).
void runAppearance(const AppearanceOptions& o) {
    std::optional<Rgb> appearance, cTT;
    if (!o.appearance.empty()) appearance = parseSrgbColour(o.appearance, "--appearance");
    if (!o.cTT.empty()) cTT = parseColour(o.cTT, "--c-tt");
    const nlohmann::json line = appearanceReport(loadYarnModel(o.model), o.model, appearance, cTT);
    std::printf("%s\n", line.dump().c_str());
}

void runEval(const EvalOptions& o) {
    checkOutputsSpareInputs({{"--model", o.model}, {"--in", o.in}}, {{"--out", o.out}});
    const YarnBsdf bsdf = YarnBsdf::load(o.model, YarnBsdfOptions{!o.noGuard});
    writeEvalValues(bsdf, o.in, o.out);
}

void runSample(const SampleOptions& o) {
    checkOutputsSpareInputs({{"--model", o.model}}, {{"--out", o.out}});
    const YarnBsdf bsdf = YarnBsdf::load(o.model, YarnBsdfOptions{!o.noGuard});
    const Vec3 wi = parseDirection(o.wi, "--wi");
    writeSamples(bsdf, wi, o.count, o.seed, true, o.out);
}

void runCheck(const CheckOptions& o) {
    if (o.threads < 0 || o.threads > 1024)
        throw InputError("--threads " + std::to_string(o.threads) +
                         " is out of range: allowed [0, 1024]");
    checkOutputsSpareInputs({{"--model", o.model}}, {}, {{"--rdm", o.rdm}}, {{"--out", o.out}});
    YarnModel model = loadYarnModel(o.model);
    // A colour-conditioned model at another colour (docs/colour.md).
    if (!o.cTT.empty()) model = model.forColour(parseColour(o.cTT, "--c-tt"), "--c-tt");
    const RdmData rdm = loadRdm(o.rdm);
    const nlohmann::json s =
        checkYarnModel(model, o.model, model.exitOffset ? exitFrameTarget(rdm) : rdm,
                       {o.minPaths, o.threads, o.dual}, o.out);
    // One line on stdout: the headline numbers (the full summary is in check.json).
    nlohmann::json line = {
        {"out", o.out},
        {"bins_checked", s.at("bins_checked")},
        {"albedo_relative_error_mean_abs", s.at("albedo").at("relative_error_mean_abs")},
        {"albedo_relative_error_worst", s.at("albedo").at("relative_error_worst")},
        {"model_albedo_max", s.at("albedo").at("model_max_all_bins")},
        {"guarded_albedo_max", s.at("energy_guard").at("albedo_max_all_bins")},
        {"m_rel_l2", s.at("m_rel_l2")},
        {"r_rel_l2", s.at("r_rel_l2")},
        {"variance_proxy", s.at("variance_proxy")},
        {"sampling_weights_worst_bin", s.at("sampling_weights").is_null()
                                           ? nlohmann::json(nullptr)
                                           : s.at("sampling_weights").at("worst_bin")},
        {"sampling_weights_worst_channel_bin",
         s.at("sampling_weights").is_null() ? nlohmann::json(nullptr)
                                            : s.at("sampling_weights").at("worst_channel_bin")},
        {"seconds", s.at("seconds")}};
    if (o.dual) {
        const nlohmann::json& d = s.at("dual_baseline");
        line["dual_baseline"] = {
            {"m_rel_l2", d.at("m_rel_l2")},
            {"r_rel_l2", d.at("r_rel_l2")},
            {"total_rel_l2", d.at("total_rel_l2")},
            {"neural_total_rel_l2", d.at("neural_total_rel_l2")},
            {"albedo_relative_error_mean_abs", d.at("albedo").at("relative_error_mean_abs")}};
    }
    std::printf("%s\n", line.dump().c_str());
}

struct AtOptions {
    std::string family, yarn, preset, out;
};

// weft yarn at: the ordinary colour model of one yarn of a family model.
void runAt(const AtOptions& o) {
    if (o.yarn.empty() == o.preset.empty())
        throw InputError("weft yarn at needs one of --yarn YARN and --preset NAME");
    checkOutputsSpareInputs({{"--family", o.family}}, {{"--out", o.out}}, {}, {});
    const FamilyModel family = loadFamilyModel(o.family);
    const YarnPoint point = o.preset.empty() ? readYarnPointArgument(o.yarn, "--yarn")
                                             : yarnPointOf(findMaterialPreset(o.preset));
    const YarnModel model = family.at(point, o.preset.empty() ? "--yarn" : "--preset " + o.preset);
    saveYarnModel(model, o.out);
    std::printf("%s\n", nlohmann::json({{"out", o.out}, {"yarn", point.toJson()}}).dump().c_str());
}

}  // namespace

YarnPoint readYarnPointArgument(const std::string& text, const std::string& flag) {
    // Inline JSON (an object) or the file holding it.
    if (!text.empty() && text.front() == '{') {
        nlohmann::json j;
        try {
            j = nlohmann::json::parse(text);
        } catch (const nlohmann::json::parse_error& e) {
            throw InputError(flag + ": malformed JSON (" + e.what() + ")");
        }
        return YarnPoint::fromJson(j, flag, "");
    }
    return YarnPoint::fromJson(readJsonFile(text), text, "");
}

void addYarnCommands(CLI::App& app) {
    CLI::App* yarn = app.add_subcommand(
        "yarn",
        "Probe the aggregated yarn BSDF of a fitted MODEL.json in the yarn frame: "
        "t = +x, b = +y, n = +z");
    yarn->require_subcommand(1);

    auto evalOpts = std::make_shared<EvalOptions>();
    CLI::App* eval = yarn->add_subcommand(
        "eval",
        "continuous part R + M of eval(wi, wo), RGB including the cosine, for every row of "
        "an (n,6) array");
    eval->add_option("--model", evalOpts->model, "fitted model (weft fit)")->required();
    eval->add_option("--in", evalOpts->in, "(n,6) float32/float64 .npy: rows wi(3), wo(3)")
        ->required();
    eval->add_option("--out", evalOpts->out, "(n,3) float64 .npy of RGB values")->required();
    eval->add_flag("--no-energy-guard", evalOpts->noGuard,
                   "the model's own S_M, even where its albedo exceeds 1");
    eval->callback([evalOpts] { runEval(*evalOpts); });

    auto sampleOpts = std::make_shared<SampleOptions>();
    CLI::App* sample = yarn->add_subcommand(
        "sample",
        "draw outgoing directions for one wi: rows wo(3), weight RGB(3), pdf(1, 0 for "
        "the delta lobe), lobe(1: 0 = T, 1 = R, 2 = M)");
    sample->add_option("--model", sampleOpts->model, "fitted model (weft fit)")->required();
    sample->add_option("--wi", sampleOpts->wi, "incident direction X,Y,Z (normalised)")->required();
    sample->add_option("--count", sampleOpts->count, "number of samples")
        ->required()
        ->check(CLI::Range(int64_t{1}, int64_t{100000000}));
    addSeedOption(*sample, sampleOpts->seed, "random seed");
    sample->add_option("--out", sampleOpts->out, "(N,8) float64 .npy")->required();
    sample->add_flag("--no-energy-guard", sampleOpts->noGuard,
                     "the model's own S_M, even where its albedo exceeds 1");
    sample->callback([sampleOpts] { runSample(*sampleOpts); });

    auto checkOpts = std::make_shared<CheckOptions>();
    CLI::App* check = yarn->add_subcommand(
        "check",
        "compare the model with a gathered RDM: directional albedo per incident bin, "
        "coarse-grid errors of R and M, sampler variance proxies, slice PNGs");
    check->add_option("--model", checkOpts->model, "fitted model (weft fit)")->required();
    check->add_option("--rdm", checkOpts->rdm, "gather directory (weft gather)")->required();
    check->add_option("--out", checkOpts->out, "report directory (written atomically)")->required();
    check
        ->add_option("--min-paths", checkOpts->minPaths,
                     "incident bins with fewer paths are left out of the albedo summary")
        ->default_val(1000)
        ->check(CLI::Range(int64_t{0}, int64_t{1} << 62));
    check->add_flag("--dual", checkOpts->dual,
                    "also compare the dual-scattering baseline (after ZMA23) of the model's "
                    "fiber and ply with the RDM: check.json's dual_baseline "
                    "(docs/dual-scattering.md)");
    check->add_option("--threads", checkOpts->threads, "worker threads (0: all cores)")
        ->default_val(0);
    check->add_option("--c-tt", checkOpts->cTT,
                      "R,G,B: check a colour-conditioned model (weft fit --colour-range) at this "
                      "fiber colour, e.g. against weft gather recolour's RDM of that colour");
    check->callback([checkOpts] { runCheck(*checkOpts); });

    auto appearanceOpts = std::make_shared<AppearanceOptions>();
    CLI::App* appearance = yarn->add_subcommand(
        "appearance",
        "the colour a yarn of a colour model looks under a uniform white sky, and the fiber "
        "colour C_TT that gives a colour (docs/colour.md, \"Colour by appearance\"): one JSON "
        "line with the model's darkest and brightest appearance per channel");
    appearance
        ->add_option("--model", appearanceOpts->model, "colour model (weft fit --colour-range)")
        ->required();
    appearance->add_option("--appearance", appearanceOpts->appearance,
                           "#rrggbb or R,G,B in [0, 1], sRGB: find the C_TT that looks this colour "
                           "(exit 2 when a channel is out of the material's reach)");
    appearance->add_option("--c-tt", appearanceOpts->cTT,
                           "R,G,B within the model's colour range: the appearance of this C_TT");
    appearance->callback([appearanceOpts] { runAppearance(*appearanceOpts); });

    auto atOpts = std::make_shared<AtOptions>();
    CLI::App* at = yarn->add_subcommand(
        "at",
        "write the ordinary colour model of one yarn of a family model (weft fit family): any "
        "N, rho, alpha, beta_R, beta_TT, gamma_TT and C_R inside its box, no gather or fit "
        "(docs/family.md)");
    at->add_option("--family", atOpts->family, "family model (weft fit family)")->required();
    at->add_option("--yarn", atOpts->yarn,
                   "the yarn: YARN.json or inline {\"fibers\": N, \"density\": RHO, \"twist\": "
                   "ALPHA, \"beta_r_deg\", \"beta_tt_deg\", \"gamma_tt_deg\", \"c_r\": [r, g, b]}");
    at->add_option("--preset", atOpts->preset,
                   "the yarn of a material preset (fleece, silk, polyester, cotton, gabardine)");
    at->add_option("--out", atOpts->out, "output model (.json, written atomically)")->required();
    at->callback([atOpts] { runAt(*atOpts); });
}

}  // namespace weft::cmd
