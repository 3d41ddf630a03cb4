// weft fit: the neural yarn model (model.json) from a gathered RDM.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.h"
#include "weft/core/error.h"
#include "weft/fit/fit.h"

namespace weft::cmd {

namespace {

struct FitCliOptions {
    std::string rdm, out, config, reference, report, recalibrate;
    uint64_t seed = 0;
    int threads = -1;
    bool quiet = false, printConfig = false, noReport = false;
};

// The fit takes minutes: a destination that cannot be written fails before it.
void requireParentDirectory(const std::string& path, const std::string& flag) {
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    std::error_code ec;
    if (!parent.empty() && !std::filesystem::is_directory(parent, ec))
        throw InputError(flag + " " + path + ": the folder " + parent.string() + " does not exist");
}

// fleece.json -> fleece-report
std::string defaultReportDir(const std::string& modelPath) {
    std::string stem = modelPath;
    if (stem.size() > 5 && stem.compare(stem.size() - 5, 5, ".json") == 0) stem.resize(stem.size() - 5);
    return stem + "-report";
}

void runFit(const FitCliOptions& c) {
    FitConfig config = c.config.empty() ? FitConfig{} : FitConfig::fromJsonFile(c.config);
    if (c.threads >= 0) config.threads = c.threads;
    if (c.printConfig) {
        std::printf("%s\n", config.toJson().dump(2).c_str());
        return;
    }
    if (c.rdm.empty() || c.out.empty()) throw InputError("weft fit needs --rdm DIR and --out MODEL.json");
    if (config.threads < 0 || config.threads > 1024)
        throw InputError("--threads " + std::to_string(config.threads) + " is out of range: allowed [0, 1024]");
    const std::string reportDir = c.report.empty() ? defaultReportDir(c.out) : c.report;
    requireParentDirectory(c.out, "--out");
    if (!c.noReport) requireParentDirectory(reportDir, "--report");
    const RdmData rdm = loadRdm(c.rdm);
    std::unique_ptr<RdmData> reference;
    if (!c.reference.empty()) reference = std::make_unique<RdmData>(loadRdm(c.reference));
    const FitResult fit = c.recalibrate.empty()
                              ? fitYarnModel(rdm, config, c.seed, c.quiet)
                              : recalibrateYarnModel(loadYarnModel(c.recalibrate), rdm, config, c.quiet);
    saveYarnModel(fit.model, c.out);
    if (!c.noReport) writeFitReport(fit, rdm, reference.get(), reportDir);
    const FitReport& r = fit.report;
    std::printf(
        "{\"out\": \"%s\", \"report\": %s, \"t_rmse\": %.5f, \"m_rel_l2\": %.4f, \"r_rel_l2\": %.4f, "
        "\"r_rel_l2_eq8\": %.4f, \"seconds\": %.1f, \"m_samples_per_second\": %.0f}\n",
        c.out.c_str(), c.noReport ? "null" : ("\"" + reportDir + "\"").c_str(), r.tRmse, r.mRelL2,
        r.rRelL2, r.rRelL2Eq8, r.seconds, r.mSamplesPerSecond);
}

}  // namespace

void addFitCommand(CLI::App& app) {
    auto o = std::make_shared<FitCliOptions>();
    CLI::App* fit = app.add_subcommand(
        "fit", "Fit the neural yarn model (T and M networks, R lobe, sampling lobe) to a gathered "
               "RDM and write MODEL.json plus a report folder (errors, loss curves, slices)");
    fit->add_option("--rdm", o->rdm, "gather directory written by weft gather");
    fit->add_option("--out", o->out, "output model file (.json, written atomically)");
    fit->add_option("--config", o->config,
                    "training configuration FIT.json (see docs/fit.md; --print-config shows the defaults)");
    addSeedOption(*fit, o->seed, "random seed of network initialisation and training samples");
    fit->add_option("--threads", o->threads, "worker threads (0: all cores; overrides the config)");
    fit->add_option("--reference", o->reference,
                    "an independent gather of the same material: adds errors against it and the "
                    "noise floor to the report");
    fit->add_option("--report", o->report, "report directory (default: MODEL path without .json + \"-report\")");
    fit->add_option("--recalibrate", o->recalibrate,
                    "an existing MODEL.json: keep its networks and R lobe, redo only the energy "
                    "calibration and the sampling lobe against --rdm (seconds instead of minutes)");
    fit->add_flag("--no-report", o->noReport, "write only the model");
    fit->add_flag("--print-config", o->printConfig, "print the configuration in effect as JSON and exit");
    fit->add_flag("--quiet", o->quiet, "no progress output");
    fit->callback([o] { runFit(*o); });
}

}  // namespace weft::cmd
