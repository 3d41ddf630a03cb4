#include "weft/fit/model_check.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <tuple>
#include <vector>

#include "weft/core/file.h"
#include "weft/core/image.h"
#include "weft/core/json_message.h"
#include "weft/core/math.h"
#include "weft/core/npy.h"
#include "weft/fit/fit.h"
#include "weft/fit/metrics.h"
#include "weft/gather/rdm_image.h"
#include "weft/yarn/dual_scattering.h"
#include "weft/yarn/yarn_bsdf.h"
#include "weft/yarn/yarn_integrals.h"

namespace weft {

namespace {

constexpr double kAlbedoTolerance = 0.03;  // the target, reported as a fraction

// Polar and azimuthal angle (degrees) of an incident bin's centre.
std::pair<double, double> binAngles(const RdmBins& bins, size_t i) {
    const Vec3 w = bins.incidentCentre(i);
    return {degrees(safeAcos(w.z)), degrees(std::atan2(w.y, w.x))};
}

// model / rdm - 1, with 0 / 0 = 0.
double relativeError(double model, double rdm) {
    if (rdm > 0) return model / rdm - 1;
    return model > 0 ? INFINITY : 0.0;
}

// a + b, elementwise.
std::vector<float> sumOf(const std::vector<float>& a, const std::vector<float>& b) {
    std::vector<float> sum(a.size());
    for (size_t k = 0; k < a.size(); ++k) sum[k] = a[k] + b[k];
    return sum;
}

}  // namespace

nlohmann::json checkDualBaseline(const YarnModel& model, const RdmData& rdm,
                                 const std::vector<float>& neuralR,
                                 const std::vector<float>& neuralM, int64_t minPaths) {
    const RdmBins& bins = rdm.bins;
    const size_t nIn = bins.incidentCount(), nOut = bins.outgoingCount();
    const DualScatteringBsdf dual(model.fiber, model.ply);
    std::vector<float> single(nIn * nOut * 3), multiple(nIn * nOut * 3);
    std::vector<Rgb> albedo(nIn);
    tbb::parallel_for(size_t(0), nIn, [&](size_t i) {
        const Vec3 wi = bins.incidentCentre(i);
        for (size_t o = 0; o < nOut; ++o) {
            const DualScatteringBsdf::Parts p = dual.parts(wi, bins.outgoingCentre(o));
            for (int c = 0; c < 3; ++c) {
                single[(i * nOut + o) * 3 + c] = static_cast<float>(p.single[c]);
                multiple[(i * nOut + o) * 3 + c] = static_cast<float>(p.multiple[c]);
            }
        }
        albedo[i] = dual.albedo(wi);
    });

    const std::vector<Rgb> rdmR = incidentEnergies(rdm.rdmR, bins);
    const std::vector<Rgb> rdmM = incidentEnergies(rdm.rdmM, bins);
    Rgb sumAbs, worst, sumModel, sumRdm;
    size_t checked = 0, within = 0;
    for (size_t i = 0; i < nIn; ++i) {
        if (rdm.count[i] < minPaths) continue;
        ++checked;
        const Rgb b = rdmR[i] + rdmM[i] + Rgb(rdm.pT[i]);
        sumModel += albedo[i];
        sumRdm += b;
        for (int c = 0; c < 3; ++c) {
            const double rel = relativeError(albedo[i][c], b[c]);
            sumAbs[c] += std::fabs(rel);
            if (std::fabs(rel) > std::fabs(worst[c])) worst[c] = rel;
            within += std::fabs(rel) <= kAlbedoTolerance;
        }
    }
    const std::vector<float> rdmTotal = sumOf(rdm.rdmR, rdm.rdmM);
    nlohmann::json j;
    j["name"] = "dual-scattering baseline (after ZMA23)";
    j["r_rel_l2"] = coarseRelativeL2(single, rdm.rdmR, bins);
    j["m_rel_l2"] = coarseRelativeL2(multiple, rdm.rdmM, bins);
    j["total_rel_l2"] = coarseRelativeL2(sumOf(single, multiple), rdmTotal, bins);
    j["neural_total_rel_l2"] = coarseRelativeL2(sumOf(neuralR, neuralM), rdmTotal, bins);
    j["bins_checked"] = checked;
    nlohmann::json& a = j["albedo"];
    const double n = static_cast<double>(checked);
    a["relative_error_mean_abs"] = checked ? rgbJson(sumAbs / n) : nlohmann::json(nullptr);
    a["relative_error_worst"] = checked ? rgbJson(worst) : nlohmann::json(nullptr);
    a["within_3_percent"] = checked ? nlohmann::json(within / (3 * n)) : nlohmann::json(nullptr);
    a["model_mean"] = checked ? rgbJson(sumModel / n) : nlohmann::json(nullptr);
    a["rdm_mean"] = checked ? rgbJson(sumRdm / n) : nlohmann::json(nullptr);
    return j;
}

YarnCheckResult computeYarnCheck(const YarnModel& model, const std::string& modelPath,
                                 const RdmData& rdm, const YarnCheckOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    const RdmBins& bins = rdm.bins;
    const size_t nIn = bins.incidentCount();
    tbb::task_arena arena(options.threads > 0 ? options.threads
                                              : tbb::this_task_arena::max_concurrency());

    // The model as fitted (the albedo comparison checks the fit), and the
    // renderer's BSDF with its energy guard (reported beside it).
    const YarnBsdf bsdf(model, modelPath, YarnBsdfOptions{false});
    std::unique_ptr<YarnBsdf> guarded;
    // (Its scales only: no sampling table.)
    arena.execute([&] {
        guarded = std::make_unique<YarnBsdf>(model, modelPath,
                                             YarnBsdfOptions{true, YarnSampling::Fitted});
    });

    // Model side: quadrature per incident bin centre (the expensive part).
    std::vector<DirectionalIntegrals> integrals(nIn);
    arena.execute([&] {
        tbb::parallel_for(size_t(0), nIn, [&](size_t i) {
            integrals[i] = integrateDirections(bsdf, bins.incidentCentre(i));
        });
    });

    // RDM side: energy of each component per incident bin.
    const std::vector<Rgb> rdmR = incidentEnergies(rdm.rdmR, bins);
    const std::vector<Rgb> rdmM = incidentEnergies(rdm.rdmM, bins);

    std::vector<double> albedoModel(nIn * 3), albedoRdm(nIn * 3), moments(nIn * 3);
    // sample()'s weights per bin (luminance): E[w] / albedo, E[w^2] / E[w]^2,
    // largest w / albedo; and the bin with the largest relative second moment.
    std::vector<double> weights(nIn * 3);
    size_t worstWeightBin = 0;
    double worstWeightRatio = -1, largestWeight = 0, smallestMean = 1e300;
    // And per colour channel, over the bright channels of each bin
    // (DirectionalIntegrals::brightChannel): the bin and channel of the
    // largest E[w_c^2] / E[w_c]^2, and the largest w_c over that channel's albedo.
    size_t worstChannelBin = 0;
    int worstChannel = 0;
    double worstChannelRatio = -1, largestChannelWeight = 0;
    std::vector<double> componentsModel(nIn * 9), componentsRdm(nIn * 9);
    Rgb sumAbs, worst, modelMax, rdmMax, sumModel, sumRdm;
    Rgb guardedMax, sumAbsGuarded, worstGuarded;
    Rgb sumModelR, sumRdmR, sumModelM, sumRdmM;
    double sumModelT = 0, sumRdmT = 0;
    nlohmann::json worstBin = nullptr;
    double worstAbs = -1;
    size_t checked = 0, within = 0, binsScaled = 0;
    double sumYarn = 0, sumUniform = 0, sumCosine = 0;
    size_t beatsCosine = 0, beatsUniform = 0;
    for (size_t i = 0; i < nIn; ++i) {
        const DirectionalIntegrals& d = integrals[i];
        const Rgb a = d.albedo(), b = rdmR[i] + rdmM[i] + Rgb(rdm.pT[i]);
        const Rgb scale = guarded->model().multipleScatteringScale(bins.incidentCentre(i));
        const Rgb g = Rgb(d.pT) + d.r + d.m * scale;
        binsScaled += !(scale == Rgb(1.0));
        for (int c = 0; c < 3; ++c) {
            componentsModel[9 * i + c] = d.pT;
            componentsModel[9 * i + 3 + c] = d.r[c];
            componentsModel[9 * i + 6 + c] = d.m[c];
            componentsRdm[9 * i + c] = rdm.pT[i];
            componentsRdm[9 * i + 3 + c] = rdmR[i][c];
            componentsRdm[9 * i + 6 + c] = rdmM[i][c];
            albedoModel[3 * i + c] = a[c];
            albedoRdm[3 * i + c] = b[c];
            modelMax[c] = std::max(modelMax[c], a[c]);
            guardedMax[c] = std::max(guardedMax[c], g[c]);
            rdmMax[c] = std::max(rdmMax[c], b[c]);
        }
        if (d.weightMean > 0) {
            const double ratio = d.weightSecondMoment / sqr(d.weightMean);
            weights[3 * i] = d.weightMean / d.albedoLuminance;
            weights[3 * i + 1] = ratio;
            weights[3 * i + 2] = d.weightMax / d.albedoLuminance;
            if (ratio > worstWeightRatio) worstWeightRatio = ratio, worstWeightBin = i;
            largestWeight = std::max(largestWeight, weights[3 * i + 2]);
            smallestMean = std::min(smallestMean, weights[3 * i]);
            for (int c = 0; c < 3; ++c) {
                if (!d.brightChannel(c)) continue;
                const double channelRatio = d.channelSecondMomentRatio(c);
                if (channelRatio > worstChannelRatio)
                    worstChannelRatio = channelRatio, worstChannelBin = i, worstChannel = c;
                largestChannelWeight =
                    std::max(largestChannelWeight, d.channelWeightMax[c] / d.channelAlbedo[c]);
            }
        }
        moments[3 * i] = d.secondMomentYarn;
        moments[3 * i + 1] = d.secondMomentUniform;
        moments[3 * i + 2] = d.secondMomentCosine;
        sumYarn += d.secondMomentYarn;
        sumUniform += d.secondMomentUniform;
        sumCosine += d.secondMomentCosine;
        beatsCosine += d.secondMomentYarn < d.secondMomentCosine;
        beatsUniform += d.secondMomentYarn < d.secondMomentUniform;
        if (rdm.count[i] < options.minPaths) continue;
        ++checked;
        sumModel += a;
        sumRdm += b;
        sumModelT += d.pT;
        sumRdmT += rdm.pT[i];
        sumModelR += d.r;
        sumRdmR += rdmR[i];
        sumModelM += d.m;
        sumRdmM += rdmM[i];
        for (int c = 0; c < 3; ++c) {
            const double rel = relativeError(a[c], b[c]);
            sumAbs[c] += std::fabs(rel);
            if (std::fabs(rel) > std::fabs(worst[c])) worst[c] = rel;
            within += std::fabs(rel) <= kAlbedoTolerance;
            const double relGuarded = relativeError(g[c], b[c]);
            sumAbsGuarded[c] += std::fabs(relGuarded);
            if (std::fabs(relGuarded) > std::fabs(worstGuarded[c])) worstGuarded[c] = relGuarded;
            if (std::fabs(rel) > worstAbs) {
                worstAbs = std::fabs(rel);
                const auto [theta, phi] = binAngles(bins, i);
                worstBin = {{"channel", c},     {"relative_error", rel}, {"theta_deg", theta},
                            {"phi_deg", phi},   {"paths", rdm.count[i]}, {"model", rgbJson(a)},
                            {"rdm", rgbJson(b)}};
            }
        }
    }

    // The same comparison on the coarse incident grid of the error metric
    // (metrics.h): per-bin RDM albedos are as noisy as a few percent in dark
    // channels even at 16M paths; pooling (path-count weighted, for model and
    // RDM alike) averages that down.
    const RdmBins coarse = kCoarseErrorBins;
    std::vector<Rgb> coarseModel(coarse.incidentCount()), coarseRdm(coarse.incidentCount());
    std::vector<double> coarseCount(coarse.incidentCount(), 0.0);
    for (size_t i = 0; i < nIn; ++i) {
        const size_t k = coarse.incidentBin(bins.incidentCentre(i));
        const double w = static_cast<double>(rdm.count[i]);
        coarseModel[k] += integrals[i].albedo() * w;
        coarseRdm[k] += (rdmR[i] + rdmM[i] + Rgb(rdm.pT[i])) * w;
        coarseCount[k] += w;
    }
    Rgb coarseSumAbs, coarseWorst;
    size_t coarseChecked = 0, coarseWithin = 0;
    for (size_t k = 0; k < coarseCount.size(); ++k) {
        if (coarseCount[k] < static_cast<double>(options.minPaths) || coarseCount[k] <= 0) continue;
        ++coarseChecked;
        for (int c = 0; c < 3; ++c) {
            const double rel = relativeError(coarseModel[k][c], coarseRdm[k][c]);
            coarseSumAbs[c] += std::fabs(rel);
            if (std::fabs(rel) > std::fabs(coarseWorst[c])) coarseWorst[c] = rel;
            coarseWithin += std::fabs(rel) <= kAlbedoTolerance;
        }
    }

    // Coarse-grid errors of the maps, the same numbers as `weft fit` reports.
    std::vector<float> mMap, rMap;
    std::vector<double> pT;
    arena.execute([&] {
        mMap = modelMultipleScatteringMap(model, bins);
        rMap = modelReflectionMap(model, bins);
        pT = modelTransmissionMap(model, bins);
    });

    const double n = static_cast<double>(checked), nAll = static_cast<double>(nIn);
    auto meanOrNull = [&](const Rgb& sum) {
        return checked ? rgbJson(sum / n) : nlohmann::json(nullptr);
    };
    auto scalarMeanOrNull = [&](double sum) {
        return checked ? nlohmann::json(sum / n) : nlohmann::json(nullptr);
    };
    int64_t paths = 0;
    for (int64_t c : rdm.count) paths += c;
    auto orNull = [&](size_t count, const nlohmann::json& value) {
        return count ? value : nlohmann::json(nullptr);
    };
    nlohmann::json summary;
    summary["model"] = modelPath;
    summary["rdm"] = rdm.dir;
    summary["bins"] = bins.toString();
    summary["paths"] = paths;
    summary["min_paths"] = options.minPaths;
    summary["bins_checked"] = checked;
    summary["bins_total"] = nIn;

    nlohmann::json& albedo = summary["albedo"];
    albedo["relative_error_mean_abs"] = meanOrNull(sumAbs);
    albedo["relative_error_worst"] = orNull(checked, rgbJson(worst));
    albedo["worst_bin"] = worstBin;
    albedo["within_3_percent"] = orNull(checked, within / (3 * n));
    albedo["model_mean"] = meanOrNull(sumModel);
    albedo["rdm_mean"] = meanOrNull(sumRdm);
    albedo["model_max_all_bins"] = rgbJson(modelMax);
    albedo["rdm_max_all_bins"] = rgbJson(rdmMax);
    nlohmann::json& components = albedo["components_mean"];
    components["model_t"] = scalarMeanOrNull(sumModelT);
    components["rdm_t"] = scalarMeanOrNull(sumRdmT);
    components["model_r"] = meanOrNull(sumModelR);
    components["rdm_r"] = meanOrNull(sumRdmR);
    components["model_m"] = meanOrNull(sumModelM);
    components["rdm_m"] = meanOrNull(sumRdmM);

    nlohmann::json& pooled = summary["albedo_coarse"];
    pooled["grid"] = std::to_string(coarse.thetaI) + "," + std::to_string(coarse.phiI);
    pooled["cells_checked"] = coarseChecked;
    pooled["relative_error_mean_abs"] =
        orNull(coarseChecked, rgbJson(coarseSumAbs / std::max<double>(1.0, coarseChecked)));
    pooled["relative_error_worst"] = orNull(coarseChecked, rgbJson(coarseWorst));
    pooled["within_3_percent"] =
        orNull(coarseChecked, coarseWithin / (3.0 * std::max<double>(1.0, coarseChecked)));

    nlohmann::json& guard = summary["energy_guard"];
    guard["active"] = guarded->model().energyGuard().active();
    guard["bins_scaled"] = binsScaled;
    guard["albedo_max_all_bins"] = rgbJson(guardedMax);
    guard["relative_error_mean_abs"] = meanOrNull(sumAbsGuarded);
    guard["relative_error_worst"] = orNull(checked, rgbJson(worstGuarded));

    summary["t_rmse"] = transmissionError(pT, rdm).weighted;
    summary["m_rel_l2"] = coarseRelativeL2(mMap, rdm.rdmM, bins);
    summary["r_rel_l2"] = coarseRelativeL2(rMap, rdm.rdmR, bins);
    summary["error_grid"] = kCoarseErrorBins.toString();

    nlohmann::json& proxy = summary["variance_proxy"];
    proxy["yarn"] = sumYarn / nAll;
    proxy["uniform_sphere"] = sumUniform / nAll;
    proxy["cosine"] = sumCosine / nAll;
    proxy["bins_where_yarn_beats_cosine"] = static_cast<double>(beatsCosine) / nAll;
    proxy["bins_where_yarn_beats_uniform"] = static_cast<double>(beatsUniform) / nAll;

    nlohmann::json& sampling = summary["sampling_weights"];
    if (worstWeightRatio >= 0) {
        const auto [theta, phi] = binAngles(bins, worstWeightBin);
        const double* w = &weights[3 * worstWeightBin];
        sampling["second_moment_ratio_max"] = worstWeightRatio;
        sampling["max_weight_over_albedo_max"] = largestWeight;
        sampling["mean_over_albedo_min"] = smallestMean;
        sampling["worst_bin"] = {{"theta_deg", theta},
                                 {"phi_deg", phi},
                                 {"mean_over_albedo", w[0]},
                                 {"second_moment_ratio", w[1]},
                                 {"max_weight_over_albedo", w[2]},
                                 {"albedo_luminance", integrals[worstWeightBin].albedoLuminance}};
        sampling["channel_second_moment_ratio_max"] = worstChannelRatio;
        sampling["channel_max_weight_over_albedo_max"] = largestChannelWeight;
        const DirectionalIntegrals& d = integrals[worstChannelBin];
        const auto [channelTheta, channelPhi] = binAngles(bins, worstChannelBin);
        const int c = worstChannel;
        sampling["worst_channel_bin"] = {
            {"theta_deg", channelTheta},
            {"phi_deg", channelPhi},
            {"channel", c},
            {"mean_over_albedo", d.channelWeightMean[c] / d.channelAlbedo[c]},
            {"second_moment_ratio", worstChannelRatio},
            {"max_weight_over_albedo", d.channelWeightMax[c] / d.channelAlbedo[c]},
            {"albedo", d.channelAlbedo[c]}};
    } else {
        sampling = nullptr;  // a black model: no weights to report
    }
    if (options.dualBaseline) {
        arena.execute([&] {
            summary["dual_baseline"] = checkDualBaseline(model, rdm, rMap, mMap, options.minPaths);
        });
    }
    summary["seconds"] =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    YarnCheckResult result;
    result.summary = std::move(summary);
    result.albedoModel = std::move(albedoModel), result.albedoRdm = std::move(albedoRdm);
    result.componentsModel = std::move(componentsModel);
    result.componentsRdm = std::move(componentsRdm);
    result.secondMoments = std::move(moments);
    result.samplingWeights = std::move(weights);
    result.rMap = std::move(rMap), result.mMap = std::move(mMap);
    return result;
}

void writeYarnCheck(const YarnCheckResult& check, const RdmData& rdm, const std::string& dir) {
    const RdmBins& bins = rdm.bins;
    const size_t ti = static_cast<size_t>(bins.thetaI), pi = static_cast<size_t>(bins.phiI);
    writeNpy(dir + "/albedo_model.npy", check.albedoModel.data(), {ti, pi, 3});
    writeNpy(dir + "/albedo_rdm.npy", check.albedoRdm.data(), {ti, pi, 3});
    writeNpy(dir + "/components_model.npy", check.componentsModel.data(), {ti, pi, 3, 3});
    writeNpy(dir + "/components_rdm.npy", check.componentsRdm.data(), {ti, pi, 3, 3});
    writeNpy(dir + "/second_moment.npy", check.secondMoments.data(), {ti, pi, 3});
    writeNpy(dir + "/sampling_weights.npy", check.samplingWeights.data(), {ti, pi, 3});

    // Albedo maps as one (1, 1, TI, PI) "slice": RDM left, model right, same exposure.
    {
        const std::vector<float> a(check.albedoRdm.begin(), check.albedoRdm.end());
        const std::vector<float> b(check.albedoModel.begin(), check.albedoModel.end());
        const RdmBins albedoBins{1, 1, bins.thetaI, bins.phiI};
        const int scale = std::max(1, 360 / std::max(bins.phiI, 1));
        writePng(dir + "/albedo.png", rdmComparisonImage(a.data(), b.data(), albedoBins, 0, scale));
    }
    writeSliceComparisons(dir, rdm, check.rMap, check.mMap);
    writeFileAtomic(dir + "/check.json", check.summary.dump(2) + "\n");
}

nlohmann::json checkYarnModel(const YarnModel& model, const std::string& modelPath,
                              const RdmData& rdm, const YarnCheckOptions& options,
                              const std::string& outDir) {
    TempDirCommit out(outDir);  // an unwritable destination fails before the work
    YarnCheckResult check = computeYarnCheck(model, modelPath, rdm, options);
    writeYarnCheck(check, rdm, out.path());
    out.commit();
    return std::move(check.summary);
}

}  // namespace weft
