// weft fit: the neural yarn model (model.json) from a gathered RDM.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.h"
#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/json_file.h"
#include "weft/core/limits.h"
#include "weft/fit/family_fit.h"
#include "weft/fit/fit.h"
#include "weft/gather/colour_paths.h"

namespace weft::cmd {

namespace {

struct FitCliOptions {
    std::string rdm, out, config, reference, report, recalibrate, ablation, colourRange;
    uint64_t seed = 0;
    int threads = -1, colourFunctions = 6;
    CLI::Option* colourFunctionsOpt = nullptr;
    bool quiet = false, printConfig = false, noReport = false;
};

// The fit takes minutes: a destination that cannot be written fails before it.
void requireParentDirectory(const std::string& path, const std::string& flag) {
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    std::error_code ec;
    if (!parent.empty() && !std::filesystem::is_directory(parent, ec))
        throw InputError(flag + " " + path + ": the folder " + parent.string() + " does not exist");
}

// A number of the summary line, or null (an ablated model has no R errors).
nlohmann::json finiteOrNull(double v) {
    return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
}

// fleece.json -> fleece-report
std::string defaultReportDir(const std::string& modelPath) {
    std::string stem = modelPath;
    if (stem.size() > 5 && stem.compare(stem.size() - 5, 5, ".json") == 0)
        stem.resize(stem.size() - 5);
    return stem + "-report";
}

void runFit(const FitCliOptions& c) {
    FitConfig config = c.config.empty() ? FitConfig{} : FitConfig::fromJsonFile(c.config);
    if (c.threads >= 0) config.threads = c.threads;
    if (c.printConfig) {
        std::printf("%s\n", config.toJson().dump(2).c_str());
        return;
    }
    // --ablation: the variants of paper Fig. 5 (docs/fit.md).
    const YarnAblation ablation = parseYarnAblation(c.ablation, "--ablation");
    if (c.rdm.empty() || c.out.empty())
        throw InputError("weft fit needs --rdm DIR and --out MODEL.json");
    if (!c.ablation.empty() && !c.recalibrate.empty())
        throw InputError(
            "--ablation cannot be combined with --recalibrate: the model file says "
            "which variant it is, and it is recalibrated as that variant");
    if (config.threads < 0 || config.threads > 1024)
        throw InputError("--threads " + std::to_string(config.threads) +
                         " is out of range: allowed [0, 1024]");
    const std::string reportDir = c.report.empty() ? defaultReportDir(c.out) : c.report;
    checkOutputsSpareInputs({{"--config", c.config}, {"--recalibrate", c.recalibrate}},
                            {{"--out", c.out}}, {{"--rdm", c.rdm}, {"--reference", c.reference}},
                            {{"--report", c.noReport ? std::string() : reportDir}});
    requireParentDirectory(c.out, "--out");
    if (!c.noReport) requireParentDirectory(reportDir, "--report");
    // --colour-range: a model for every C_TT of the range (docs/colour.md).
    std::unique_ptr<ColourFitOptions> colour;
    std::vector<ColourPath> colourPaths;
    if (!c.colourRange.empty()) {
        if (!c.ablation.empty() || !c.recalibrate.empty())
            throw InputError("--colour-range cannot be combined with --ablation or --recalibrate");
        colour = std::make_unique<ColourFitOptions>();
        colour->range = parseColourRange(c.colourRange, "--colour-range");
        checkRange("--colour-functions =", c.colourFunctions, 2, ColourBasis::kMaxFunctions);
        colour->functions = c.colourFunctions;
    } else if (c.colourFunctionsOpt->count()) {
        throw InputError("--colour-functions needs --colour-range LO,HI");
    }
    const RdmData rdm = loadRdm(c.rdm);
    if (colour) {
        colourPaths = loadColourPaths(c.rdm);
        colour->paths = &colourPaths;
    }
    std::unique_ptr<RdmData> reference;
    if (!c.reference.empty()) reference = std::make_unique<RdmData>(loadRdm(c.reference));
    std::unique_ptr<YarnModel> recalibrated;
    if (!c.recalibrate.empty()) {
        recalibrated = std::make_unique<YarnModel>(loadYarnModel(c.recalibrate));
        // A conditioned model is recalibrated from the gather's recorded paths.
        if (recalibrated->colour) colourPaths = loadColourPaths(c.rdm);
    }
    const FitResult fit =
        c.recalibrate.empty()
            ? fitYarnModel(rdm, config, c.seed, c.quiet, ablation, colour.get())
            : recalibrateYarnModel(*recalibrated, rdm, config, c.quiet,
                                   recalibrated->colour ? &colourPaths : nullptr);
    saveYarnModel(fit.model, c.out);
    if (!c.noReport) {
        // The model is measured against what it was fitted to (fit.h, fitTarget).
        std::unique_ptr<RdmData> referenceTarget;
        if (reference)
            referenceTarget = std::make_unique<RdmData>(fitTarget(*reference, fit.model));
        writeFitReport(fit, fitTarget(rdm, fit.model), referenceTarget.get(), reportDir);
    }
    const FitReport& r = fit.report;
    nlohmann::ordered_json summary = {
        {"out", c.out},
        {"report", c.noReport ? nlohmann::ordered_json() : nlohmann::ordered_json(reportDir)},
        {"ablation", yarnAblationName(fit.model.ablation)},
        {"t_rmse", r.tRmse},
        {"m_rel_l2", r.mRelL2},
        {"r_rel_l2", finiteOrNull(r.rRelL2)},
        {"r_rel_l2_eq8", finiteOrNull(r.rRelL2Eq8)},
        {"seconds", r.seconds},
        {"m_samples_per_second", r.mSamplesPerSecond}};
    if (colour || fit.model.colour) summary["colour"] = r.colour;
    std::printf("%s\n", summary.dump().c_str());
}

struct FamilyFitCliOptions {
    std::string gather, out, config, recalibrate, colourRange = "0.3,0.999";
    uint64_t seed = 0;
    int threads = -1, colourFunctions = 6;
    bool quiet = false, printConfig = false, calibrateM = false;
};

void runFitFamily(const FamilyFitCliOptions& c) {
    FamilyFitOptions options;
    if (!c.config.empty()) {
        // The family's defaults, then the file's keys over them.
        nlohmann::json merged = options.config.toJson();
        merged.merge_patch(readJsonFile(c.config));
        options.config = FitConfig::fromJson(merged, c.config);
    }
    if (c.threads >= 0) options.config.threads = c.threads;
    if (c.printConfig) {
        std::printf("%s\n", options.config.toJson().dump(2).c_str());
        return;
    }
    if (c.gather.empty() || c.out.empty())
        throw InputError("weft fit family needs --gather DIR and --out FAMILY.json");
    checkRange("--threads", options.config.threads, 0, 1024);
    options.range = parseColourRange(c.colourRange, "--colour-range");
    checkRange("--colour-functions =", c.colourFunctions, 2, ColourBasis::kMaxFunctions);
    options.functions = c.colourFunctions;
    options.seed = c.seed;
    options.quiet = c.quiet;
    options.calibrateM = c.calibrateM;
    checkOutputsSpareInputs({{"--config", c.config}, {"--recalibrate", c.recalibrate}},
                            {{"--out", c.out}}, {{"--gather", c.gather}}, {});
    requireParentDirectory(c.out, "--out");
    if (!c.recalibrate.empty()) {
        options.recalibrate = loadFamilyModel(c.recalibrate);
        // The model's own colour range, not the option's default.
        options.range = options.recalibrate->colour.range();
    }
    const FamilyGather gather = loadFamilyGather(c.gather);
    const FamilyFitResult fit = fitFamilyModel(gather, options);
    saveFamilyModel(fit.model, c.out);
    const nlohmann::json& r = fit.model.fit;
    nlohmann::ordered_json summary = {{"out", c.out},
                                      {"yarns", gather.points.size()},
                                      {"t_rmse", r.at("t_rmse")},
                                      {"masking", r.value("masking", nlohmann::json())},
                                      {"calibration", r.value("calibration", nlohmann::json())},
                                      {"seconds", r.at("seconds")},
                                      {"m_samples_per_second", r.at("m_samples_per_second")}};
    std::printf("%s\n", summary.dump().c_str());
}

}  // namespace

void addFitCommand(CLI::App& app) {
    auto o = std::make_shared<FitCliOptions>();
    CLI::App* fit = app.add_subcommand(
        "fit",
        "Fit the neural yarn model (T and M networks, R lobe, sampling lobe) to a gathered "
        "RDM and write MODEL.json plus a report folder (errors, loss curves, slices)");
    fit->add_option("--rdm", o->rdm, "gather directory written by weft gather");
    fit->add_option("--out", o->out, "output model file (.json, written atomically)");
    fit->add_option(
        "--config", o->config,
        "training configuration FIT.json (see docs/fit.md; --print-config shows the defaults)");
    addSeedOption(*fit, o->seed, "random seed of network initialisation and training samples");
    fit->add_option("--threads", o->threads, "worker threads (0: all cores; overrides the config)");
    fit->add_option("--reference", o->reference,
                    "an independent gather of the same material: adds errors against it and the "
                    "noise floor to the report");
    fit->add_option("--report", o->report,
                    "report directory (default: MODEL path without .json + \"-report\")");
    fit->add_option("--recalibrate", o->recalibrate,
                    "an existing MODEL.json: keep its networks and R lobe, redo only the energy "
                    "calibration and the sampling lobe against --rdm (seconds instead of minutes)");
    fit->add_option("--ablation", o->ablation,
                    "fit an ablated variant of paper Fig. 5 instead of the full model: naive (one "
                    "network over the whole RDM, no T or R) or no-r-lobe (no analytic R lobe; the "
                    "M network also carries R); see docs/fit.md");
    fit->add_option("--colour-range", o->colourRange,
                    "LO,HI (0 < LO < HI <= 1, e.g. 0.3,0.999): fit a model for every fiber colour "
                    "C_TT in the range, per channel, from a gather made with --any-colour "
                    "(docs/colour.md)");
    o->colourFunctionsOpt = fit->add_option(
        "--colour-functions", o->colourFunctions,
        "with --colour-range: the number K of colour functions (2..12, default 6)");
    fit->add_flag("--no-report", o->noReport, "write only the model");
    fit->add_flag("--print-config", o->printConfig,
                  "print the configuration in effect as JSON and exit");
    fit->add_flag("--quiet", o->quiet, "no progress output");
    auto fo = std::make_shared<FamilyFitCliOptions>();
    CLI::App* family = fit->add_subcommand(
        "family",
        "Fit a family model (FAMILY.json: one model for every yarn of a box of yarn parameters) "
        "to a family gather written by weft gather family (docs/family.md)");
    family->add_option("--gather", fo->gather, "family gather directory (weft gather family)");
    family->add_option("--out", fo->out, "output family model (.json, written atomically)");
    family->add_option("--config", fo->config,
                       "training configuration FIT.json over the family's defaults (--print-config "
                       "shows them; energy_calibration_degree: 6 by default, -1 for none, "
                       "docs/family.md)");
    addSeedOption(*family, fo->seed, "random seed of network initialisation and training samples");
    family->add_option("--threads", fo->threads, "worker threads (0: all cores)");
    family->add_option("--recalibrate", fo->recalibrate,
                       "refit the energy calibration of this family model (FAMILY.json) only, "
                       "at the configuration's energy_calibration_degree, and write it to --out");
    family->add_flag("--calibrate-m", fo->calibrateM,
                     "calibrate the M lobe's energy too (by default only R's: measured, M's made "
                     "the albedo worse; docs/family.md)");
    family->add_option("--colour-range", fo->colourRange,
                       "LO,HI: the fiber colours C_TT the model covers, per channel "
                       "(0 < LO < HI <= 1; default 0.3,0.999)");
    family->add_option("--colour-functions", fo->colourFunctions,
                       "the number K of colour functions (2..12, default 6)");
    family->add_flag("--print-config", fo->printConfig,
                     "print the configuration in effect as JSON and exit");
    family->add_flag("--quiet", fo->quiet, "no progress output");
    family->callback([fo] { runFitFamily(*fo); });
    fit->require_subcommand(0, 1);
    fit->callback([o, family] {
        if (!family->parsed()) runFit(*o);
    });
}

}  // namespace weft::cmd
