// Orchestration of weft fit (fit.h): the five steps in order, ablations,
// recalibration and the fit record stored in model.json.
#include "weft/fit/fit.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <utility>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/fit/metrics.h"
#include "weft/yarn/material_preset.h"
#include "weft/yarn/yarn_appearance.h"
#include "weft/yarn/yarn_lobes.h"

namespace weft {

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The fit record's entry for a calibration by colour: its degree and the
// nodes' summaries (fitColourCalibration); null without one.
nlohmann::json colourCalibrationRecord(const ColourCalibration& byColour,
                                       const nlohmann::json& nodes) {
    if (byColour.empty()) return nullptr;
    return {{"form", "by colour"}, {"degree", byColour.nodes[0].degree}, {"nodes", nodes}};
}

// Steps 4 and 5 of the fit on a model whose networks and R lobe are in place;
// rFit and mFit are its R and M maps on the RDM's bins (updated).
void finishFit(YarnModel& model, const RdmData& rdm, const FitConfig& config, int threads,
               bool quiet, std::vector<float>& rFit, std::vector<float>& mFit, FitReport& report) {
    const RdmBins& bins = rdm.bins;
    tbb::task_arena arena(threads);
    auto phase = Clock::now();
    auto phaseDone = [&](const char* what) {
        if (!quiet) std::fprintf(stderr, "fit: %s in %.1fs\n", what, secondsSince(phase));
        phase = Clock::now();
    };
    // 4. Energy calibration of R and M (energy_calibration.h).
    report.mRelL2Uncalibrated = report.mRelL2;
    report.rRelL2Uncalibrated = report.rRelL2;
    model.calibration = EnergyCalibration{};
    report.calibration = nullptr;
    if (config.calibrationDegree >= 0) {
        model.calibration = fitEnergyCalibration(model, rdm, config.calibrationDegree, threads,
                                                 &report.calibration);
        arena.execute([&] {
            rFit = modelReflectionMap(model, bins);
            mFit = modelMultipleScatteringMap(model, bins);
        });
        report.rRelL2 = coarseRelativeL2(rFit, rdm.rdmR, bins);
        report.mRelL2 = coarseRelativeL2(mFit, rdm.rdmM, bins);
        phaseDone("energy calibration");
    }
    // 5. Sampling parameters.
    const double rEnergy = mapEnergy(rFit, bins), mEnergy = mapEnergy(mFit, bins);
    const double kappaR = rEnergy + mEnergy > 0 ? rEnergy / (rEnergy + mEnergy) : 0.5;
    model.sampling = fitSamplingLobe(model, mFit, bins, kappaR, &report.mSecondMoment, threads);
    phaseDone("sampling lobe");
}

// 6. A colour model's appearance table (yarn_appearance.h), which a scene's
// "appearance" inverts to a C_TT; its seconds go into `colourRecord`.
void tabulateAppearance(YarnModel& model, int nodes, int threads, bool quiet,
                        nlohmann::json& colourRecord) {
    const auto start = Clock::now();
    tbb::task_arena arena(threads);
    double adjusted = 0;
    arena.execute(
        [&] { model.appearance = computeAppearanceTable(model, "fit", nodes, &adjusted); });
    const double seconds = secondsSince(start);
    colourRecord["appearance"] = {{"nodes", model.appearance->cTT.size()},
                                  {"monotone_adjustment", adjusted},
                                  {"seconds", seconds}};
    if (!quiet)
        std::fprintf(stderr, "fit: appearance at %zu greys in %.1fs\n",
                     model.appearance->cTT.size(), seconds);
}

nlohmann::json fitRecord(const FitReport& report, const FitConfig& config, uint64_t seed,
                         const RdmData& rdm, YarnAblation ablation) {
    nlohmann::json fit;
    fit = {{"t_rmse", report.tRmse},
                 {"t_rmse_unweighted", report.tRmseUnweighted},
                 {"m_rel_l2", report.mRelL2},
                 {"r_rel_l2", report.rRelL2},
                 {"r_rel_l2_eq8", report.rRelL2Eq8},
                 {"r_energy_ratio", report.rEnergyRatio},
                 {"m_second_moment", report.mSecondMoment},
                 {"seconds", report.seconds},
                 {"m_samples_per_second", report.mSamplesPerSecond},
                 {"seed", seed},
                 {"config", config.toJson()},
                 {"rdm",
                  {{"path", recordedPath(rdm.dir)},
                   {"paths", rdm.meta.value("paths", nlohmann::json())},
                   {"seed", rdm.meta.value("seed", nlohmann::json())},
                   {"ply_seed", rdm.meta.value("ply_seed", nlohmann::json())},
                   {"bins", rdm.meta.value("bins", nlohmann::json())}}}};
    if (config.masking) fit["r_rel_l2_masked"] = report.rRelL2Masked;
    if (ablation != YarnAblation::None) {
        // No R lobe: its errors would compare two zero maps.
        fit["ablation"] = yarnAblationName(ablation);
        for (const char* key : {"r_rel_l2", "r_rel_l2_eq8", "r_energy_ratio", "r_rel_l2_masked"})
            fit.erase(key);
    }
    if (config.calibrationDegree >= 0) {
        fit["m_rel_l2_uncalibrated"] = report.mRelL2Uncalibrated;
        if (ablation == YarnAblation::None)
            fit["r_rel_l2_uncalibrated"] = report.rRelL2Uncalibrated;
        fit["energy_calibration"] = report.calibration;
    }
    return fit;
}

// The t_net of a naive model: the format needs a 3 -> 1 sigmoid network, and
// this one is 0 to float precision (sigmoid(-100)), should anything read it,
// although YarnBsdf and the model maps never do.
NetworkWeights zeroTransmissionNetwork() {
    NetworkWeights net;
    net.output = OutputFunction::Sigmoid;
    net.layers.push_back({3, 1, {0.0f, 0.0f, 0.0f}, {-100.0f}, {}});
    return net;
}

// Step 7: the exit-offset table of a full model of one colour (a
// conditioned model's offsets would be those of one colour; an ablated
// model's M lobe holds light that does not travel as M light does).
ExitOffsetTable fitExitOffset(const RdmData& rdm, YarnAblation ablation, bool conditioned) {
    if (conditioned || ablation != YarnAblation::None)
        throw InputError("fit configuration: exit_offset is for a full model of one colour, not " +
                         std::string(conditioned ? "a colour-conditioned one" : "an ablation"));
    if (rdm.exitOffset.empty())
        throw InputError(rdm.dir +
                         ": no exit_offset.npy (a gather made before exit offsets were "
                         "recorded, or a merge with such a part): gather again, or "
                         "fit with \"exit_offset\": false");
    return ExitOffsetTable::fromHistogram(rdm.exitOffset, ExitOffsetTable::defaultEdges(),
                                          rdm.dir + "/exit_offset.npy");
}

}  // namespace

RdmData exitFrameTarget(const RdmData& rdm) {
    if (rdm.rdmMExit.empty())
        throw InputError(rdm.dir +
                         ": no rdm_m_exit.npy (a gather made before M was binned in the "
                         "exit frame, or a merge with such a part): gather again");
    RdmData target = rdm;
    target.rdmM = rdm.rdmMExit;
    return target;
}

RdmData fitTarget(const RdmData& rdm, const YarnModel& model) {
    if (model.ablation != YarnAblation::None) return ablationTarget(rdm, model.ablation);
    if (model.exitOffset) return exitFrameTarget(rdm);
    return rdm;
}

size_t transmissionOutgoingBin(const RdmBins& bins, size_t incidentBin) {
    return bins.outgoingBin(-bins.incidentCentre(incidentBin));
}

RdmData ablationTarget(const RdmData& rdm, YarnAblation ablation) {
    if (ablation == YarnAblation::None) return rdm;
    RdmData target;
    target.dir = rdm.dir;
    target.meta = rdm.meta;
    target.bins = rdm.bins;
    target.count = rdm.count;
    target.pT = rdm.pT;
    target.rdmM.resize(rdm.rdmM.size());
    for (size_t k = 0; k < rdm.rdmM.size(); ++k) target.rdmM[k] = rdm.rdmR[k] + rdm.rdmM[k];
    target.rdmR.assign(rdm.rdmR.size(), 0.0f);
    if (ablation == YarnAblation::Naive) {
        const RdmBins& bins = rdm.bins;
        const size_t nOut = bins.outgoingCount();
        for (size_t i = 0; i < bins.incidentCount(); ++i) {
            // All of T in the one bin of -wi (at the incident bin's centre):
            // the bin average of the delta lobe, so its energy is kept exactly.
            const size_t o = transmissionOutgoingBin(bins, i);
            const double density = rdm.pT[i] / bins.outgoingSolidAngle(o);
            for (int c = 0; c < 3; ++c)
                target.rdmM[(i * nOut + o) * 3 + c] += static_cast<float>(density);
            target.pT[i] = 0;
        }
    }
    return target;
}

FitResult fitYarnModel(const RdmData& gathered, const FitConfig& config, uint64_t seed, bool quiet,
                       YarnAblation ablation, const ColourFitOptions* colour) {
    if (colour && ablation != YarnAblation::None)
        throw InputError("a colour-conditioned fit has no ablations");
    // Before any training: networks and a calibration that the renderer runs.
    config.validate("fit configuration");
    const auto t0 = Clock::now();
    // Where M light leaves the ply (step 7), first: a gather without its
    // offsets fails before the training.
    std::optional<ExitOffsetTable> exitOffset;
    if (config.exitOffset) exitOffset = fitExitOffset(gathered, ablation, colour != nullptr);
    // Every step below sees the model's target: the ablated model's, or M in
    // the exit frame for a model with exit offsets; else the gather itself.
    RdmData target;
    if (ablation != YarnAblation::None) target = ablationTarget(gathered, ablation);
    if (exitOffset) target = exitFrameTarget(gathered);
    const RdmData& rdm = ablation != YarnAblation::None || exitOffset ? target : gathered;
    const RdmBins& bins = rdm.bins;
    const int threads = config.threads > 0 ? config.threads : tbb::this_task_arena::max_concurrency();
    tbb::task_arena arena(threads);

    // One line per phase on stderr (the long ones also have a progress bar).
    auto phaseDone = [&](const char* what, Clock::time_point since) {
        if (!quiet) std::fprintf(stderr, "fit: %s in %.1fs\n", what, secondsSince(since));
    };
    FitResult result;
    YarnModel& model = result.model;
    FitReport& report = result.report;
    model.ablation = ablation;
    try {
        model.fiber = FiberParams::fromJson(rdm.meta.at("fiber"), rdm.dir + "/meta.json: fiber");
        const auto& ply = rdm.meta.at("ply");
        model.ply = {ply.at("fibers").get<int>(), ply.at("density").get<double>(),
                     ply.at("twist").get<double>()};
    } catch (const nlohmann::json::exception& e) {
        throw InputError(rdm.dir + "/meta.json: missing or malformed fiber/ply block (" + e.what() + ")");
    }
    model.ply.validate();

    // 1. T network (none for the naive model, whose P(T) is 0).
    auto phase = Clock::now();
    model.tNet = model.hasTransmissionLobe()
                     ? fitTransmissionNetwork(rdm, config, seed, arena, quiet, &report.tLoss)
                     : zeroTransmissionNetwork();
    report.tSeconds = secondsSince(phase);
    phase = Clock::now();
    const TransmissionError tError = transmissionError(modelTransmissionMap(model, bins), rdm);
    report.tRmse = tError.weighted;
    report.tRmseUnweighted = tError.unweighted;

    // 2. R lobe: plain eq. 8, then the masking term. Ablated models have
    // none (a zero map), but keep the tilt: the M sampling lobe lives in the
    // surface fiber frame.
    model.rLobe.tiltDeg = SurfaceFiberFrame::tiltDegOfTwist(model.ply.twist);
    model.rLobe.masking.clear();
    std::vector<float> rEq8, rFit;  // plain eq. 8; the R lobe as stored in the model
    arena.execute([&] { rEq8 = modelReflectionMap(model, bins); });
    report.rRelL2Masked = std::numeric_limits<double>::quiet_NaN();
    if (model.hasReflectionLobe()) {
        report.rRelL2Eq8 = coarseRelativeL2(rEq8, rdm.rdmR, bins);
        report.rEnergyRatio = mapEnergy(rdm.rdmR, bins) / mapEnergy(rEq8, bins);
        phaseDone("R lobe (eq. 8)", phase);
    } else {
        report.rRelL2 = report.rRelL2Eq8 = report.rEnergyRatio = report.rRelL2Masked;
    }
    phase = Clock::now();
    if (!model.hasReflectionLobe()) {
        rFit = std::move(rEq8);
    } else if (config.masking) {
        model.rLobe.masking = fitMaskingCoefficients(rEq8, rdm.rdmR, bins);
        arena.execute([&] { rFit = modelReflectionMap(model, bins); });
        report.rRelL2Masked = coarseRelativeL2(rFit, rdm.rdmR, bins);
        report.rRelL2 = report.rRelL2Masked;
        phaseDone("R masking term", phase);
    } else {
        report.rRelL2 = report.rRelL2Eq8;
        rFit = std::move(rEq8);
    }

    // 3. M network: for the gathered colour, or for every colour of the range.
    phase = Clock::now();
    std::unique_ptr<ColourTargets> targets;
    if (colour) {
        const ColourBasisFit basis = fitColourBasis(*colour->paths, bins, rdm.count,
                                                    colour->range, colour->functions);
        phaseDone("colour functions", phase);
        phase = Clock::now();
        targets = std::make_unique<ColourTargets>(*colour->paths, bins, rdm.count);
        model.mNet = fitColourConditionedMNetwork(*targets, basis.basis, config, seed, arena,
                                                  quiet, &report.mLoss);
        model.colour = basis.basis;
        report.colour = {{"functions", colour->functions},
                         {"c_tt_range", {colour->range.lo, colour->range.hi}},
                         {"basis_rows", basis.rows},
                         {"basis_error_mean", basis.meanError},
                         {"basis_error_worst", basis.worstError}};
    } else {
        model.mNet = fitMultipleScatteringNetwork(rdm, config, seed, arena, quiet, &report.mLoss);
    }
    report.mSeconds = secondsSince(phase);
    report.mSamplesPerSecond =
        static_cast<double>(config.m.steps) * config.m.batch / std::max(report.mSeconds, 1e-9);
    std::vector<float> mFit;
    arena.execute([&] { mFit = modelMultipleScatteringMap(model, bins); });
    report.mRelL2 = coarseRelativeL2(mFit, rdm.rdmM, bins);
    phase = Clock::now();

    if (colour) {
        // M at test colours against the RDM of that colour from the records.
        nlohmann::json byColour = nlohmann::json::array();
        for (const Rgb& c : colourFitTestColours(colour->range)) {
            std::vector<float> fitted, target;
            arena.execute([&] {
                fitted = conditionedMultipleScatteringMap(model.mNet, *model.colour, bins, c);
                target = targets->map(c);
            });
            byColour.push_back(
                {{"c_tt", {c.r, c.g, c.b}}, {"m_rel_l2", coarseRelativeL2(fitted, target, bins)}});
        }
        report.colour["m_rel_l2_by_colour"] = byColour;
        // 4. The energy calibration by colour: one per node colour, from the
        // records recoloured to it (fitColourCalibration).
        if (config.calibrationDegree >= 0) {
            nlohmann::json nodes;
            model.colourCalibration = fitColourCalibration(
                model, rdm, *colour->paths, config.calibrationDegree, threads, &nodes);
            report.colour["energy_calibration"] =
                colourCalibrationRecord(model.colourCalibration, nodes);
            if (!quiet)
                std::fprintf(stderr, "fit: energy calibration at %zu colours in %.1fs\n",
                             model.colourCalibration.nodes.size(), secondsSince(phase));
            phase = Clock::now();
        }
        // 5. The sampling lobe of the gathered colour (fitted on the maps of
        // the uncalibrated model, as a one-colour fit's is).
        FitConfig oneColour = config;
        oneColour.calibrationDegree = -1;
        YarnModel own = model.forColour(model.ownColourInRange(), "fit");
        finishFit(own, rdm, oneColour, threads, quiet, rFit, mFit, report);
        model.sampling = own.sampling;
        tabulateAppearance(model, config.appearanceNodes, threads, quiet, report.colour);
    } else {
        // 4-5. Energy calibration and sampling lobe.
        finishFit(model, rdm, config, threads, quiet, rFit, mFit, report);
    }
    if (!model.hasReflectionLobe())
        report.rRelL2 = report.rRelL2Uncalibrated = std::numeric_limits<double>::quiet_NaN();
    // 7. Where M light leaves the ply: the gather's histogram, merged.
    model.exitOffset = std::move(exitOffset);

    report.seconds = secondsSince(t0);
    model.fit = fitRecord(report, config, seed, rdm, ablation);
    if (colour) {
        model.fit["colour"] = report.colour;
        model.fit.erase("energy_calibration");
    }
    return result;
}

std::vector<Rgb> colourFitTestColours(const ColourRange& range) {
    // The Table 3 colours (docs/design.md 3) and three greys, clamped into the range.
    std::vector<Rgb> colours;
    for (const MaterialPreset& p : materialPresets()) colours.push_back(p.fiber.cTT);
    for (double g : {0.0, 0.5, 1.0}) colours.push_back(Rgb(range.lo + g * (range.hi - range.lo)));
    for (Rgb& c : colours)
        for (int k = 0; k < 3; ++k) c[k] = std::clamp(c[k], range.lo, range.hi);
    return colours;
}

namespace {

// What a recalibration keeps, measured before steps 4-5: the R and M maps of
// `model` on the RDM's bins (for finishFit) and the errors of R, M and T, with
// eq. 8's R error from the original record of `fitted`.
void measureKeptParts(const YarnModel& model, const YarnModel& fitted, const RdmData& rdm,
                      int threads, std::vector<float>* rFit, std::vector<float>* mFit,
                      FitReport& report) {
    tbb::task_arena arena(threads);
    arena.execute([&] {
        *rFit = modelReflectionMap(model, rdm.bins);
        *mFit = modelMultipleScatteringMap(model, rdm.bins);
    });
    report.rRelL2 = coarseRelativeL2(*rFit, rdm.rdmR, rdm.bins);
    report.mRelL2 = coarseRelativeL2(*mFit, rdm.rdmM, rdm.bins);
    report.tRmse = model.hasTransmissionLobe()
                       ? transmissionError(modelTransmissionMap(model, rdm.bins), rdm).weighted
                       : 0.0;
    report.rRelL2Eq8 = fitted.fit.value("r_rel_l2_eq8", 0.0);
}

// The fit record's "recalibrated" entry.
nlohmann::json recalibratedEntry(const RdmData& rdm, const FitConfig& config, double seconds) {
    return {{"rdm", recordedPath(rdm.dir)},
            {"energy_calibration_degree", config.calibrationDegree},
            {"seconds", seconds}};
}

// recalibrateYarnModel for a colour-conditioned model (fit.h).
FitResult recalibrateConditioned(const YarnModel& fitted, const RdmData& rdm,
                                 const FitConfig& config, bool quiet,
                                 const std::vector<ColourPath>* paths) {
    if (!paths)
        throw InputError("--recalibrate: " + rdm.dir +
                         " has no recorded paths; a colour-conditioned model is recalibrated "
                         "from a gather made with --any-colour");
    const auto t0 = Clock::now();
    const int threads = config.threads > 0 ? config.threads : tbb::this_task_arena::max_concurrency();
    FitResult result;
    result.model = fitted;
    YarnModel& model = result.model;
    FitReport& report = result.report;
    nlohmann::json nodes = nullptr;
    model.colourCalibration = {};
    if (config.calibrationDegree >= 0)
        model.colourCalibration =
            fitColourCalibration(model, rdm, *paths, config.calibrationDegree, threads, &nodes);
    // The errors and the sampling lobe at the gathered colour, on the model
    // without its calibration, as a conditioned fit has them.
    YarnModel uncalibrated = model;
    uncalibrated.colourCalibration = {};
    YarnModel own = uncalibrated.forColour(model.ownColourInRange(), "--recalibrate");
    std::vector<float> rFit, mFit;
    measureKeptParts(own, fitted, rdm, threads, &rFit, &mFit, report);
    FitConfig oneColour = config;
    oneColour.calibrationDegree = -1;
    finishFit(own, rdm, oneColour, threads, quiet, rFit, mFit, report);
    model.sampling = own.sampling;
    report.colour = fitted.fit.value("colour", nlohmann::json::object());
    report.colour["energy_calibration"] = colourCalibrationRecord(model.colourCalibration, nodes);
    tabulateAppearance(model, config.appearanceNodes, threads, quiet, report.colour);
    report.seconds = secondsSince(t0);
    nlohmann::json record = fitted.fit;
    record["colour"] = report.colour;
    record["m_second_moment"] = report.mSecondMoment;
    record["recalibrated"] = recalibratedEntry(rdm, config, report.seconds);
    model.fit = record;
    return result;
}

}  // namespace

FitResult recalibrateYarnModel(const YarnModel& fitted, const RdmData& gathered,
                               const FitConfig& config, bool quiet,
                               const std::vector<ColourPath>* paths) {
    config.validate("fit configuration");
    if (fitted.colour) return recalibrateConditioned(fitted, gathered, config, quiet, paths);
    const auto t0 = Clock::now();
    // What it was fitted to: its ablation's target, or M in the exit frame.
    const RdmData rdm = fitTarget(gathered, fitted);
    const int threads = config.threads > 0 ? config.threads : tbb::this_task_arena::max_concurrency();
    FitResult result;
    result.model = fitted;
    YarnModel& model = result.model;
    FitReport& report = result.report;
    model.calibration = EnergyCalibration{};
    std::vector<float> rFit, mFit;
    measureKeptParts(model, fitted, rdm, threads, &rFit, &mFit, report);
    finishFit(model, rdm, config, threads, quiet, rFit, mFit, report);
    report.seconds = secondsSince(t0);
    // Keep the original record (training errors, timings, seed); update what moved.
    nlohmann::json record = fitted.fit;
    record["t_rmse"] = report.tRmse;
    record["m_rel_l2"] = report.mRelL2;
    record["m_rel_l2_uncalibrated"] = report.mRelL2Uncalibrated;
    if (model.hasReflectionLobe()) {
        record["r_rel_l2"] = report.rRelL2;
        record["r_rel_l2_uncalibrated"] = report.rRelL2Uncalibrated;
    } else {
        report.rRelL2 = report.rRelL2Uncalibrated = report.rRelL2Eq8 =
            std::numeric_limits<double>::quiet_NaN();
    }
    record["m_second_moment"] = report.mSecondMoment;
    record["energy_calibration"] = report.calibration;
    record["recalibrated"] = recalibratedEntry(rdm, config, report.seconds);
    model.fit = record;
    return result;
}

}  // namespace weft
