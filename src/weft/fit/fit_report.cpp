// The report next to a fitted model (weft fit): errors, loss curves, slices.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <tuple>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/image.h"
#include "weft/core/math.h"
#include "weft/core/plot.h"
#include "weft/fit/fit.h"
#include "weft/fit/metrics.h"
#include "weft/gather/rdm_image.h"

namespace weft {

namespace {

nlohmann::json finiteOrNull(double v) {
    return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
}

// Incident directions of the slice pictures: normal, oblique and grazing, along and across t.
struct SliceDirection {
    double thetaDeg, phiDeg;
};
constexpr SliceDirection kSliceDirections[] = {{10, 0}, {45, 0}, {45, 90}, {75, 0}, {75, 90}};

}  // namespace

void writeSliceComparisons(const std::string& dir, const RdmData& rdm,
                           const std::vector<float>& rMap, const std::vector<float>& mMap) {
    const RdmBins& bins = rdm.bins;
    for (const SliceDirection& d : kSliceDirections) {
        const size_t bin =
            bins.incidentBin(sphericalDirection(radians(d.thetaDeg), radians(d.phiDeg)));
        for (const auto& [name, rdmMap, modelMap] :
             {std::tuple{"m", &rdm.rdmM, &mMap}, std::tuple{"r", &rdm.rdmR, &rMap}}) {
            const Image exposureSource = rdmSliceImage(rdmMap->data(), bins, bin);
            const Image image = rdmComparisonImage(rdmMap->data(), modelMap->data(), bins, bin);
            char file[96];
            std::snprintf(file, sizeof file, "/slice-%s-theta%02.0f-phi%03.0f.png", name,
                          d.thetaDeg, d.phiDeg);
            writePng(dir + file, image, quantileExposure(exposureSource));
        }
    }
}

void writeFitReport(const FitResult& fit, const RdmData& rdm, const RdmData* reference,
                    const std::string& dir) {
    const FitReport& r = fit.report;
    const RdmBins& bins = rdm.bins;
    TempDirCommit out(dir);

    nlohmann::json errors = {
        {"t_rmse", r.tRmse},
        {"t_rmse_unweighted", r.tRmseUnweighted},
        {"m_rel_l2", r.mRelL2},
        {"r_rel_l2", r.rRelL2},
        {"r_rel_l2_eq8", r.rRelL2Eq8},
        {"r_rel_l2_masked", finiteOrNull(r.rRelL2Masked)},
        {"r_energy_ratio_rdm_over_eq8", r.rEnergyRatio},
        {"m_second_moment", r.mSecondMoment},
        {"error_grid", kCoarseErrorBins.toString()},
        {"seconds", {{"total", r.seconds}, {"t_net", r.tSeconds}, {"m_net", r.mSeconds}}},
        {"m_training_samples_per_second", r.mSamplesPerSecond},
        {"rdm", recordedPath(rdm.dir)},
    };
    const std::vector<float> mFit = modelMultipleScatteringMap(fit.model, bins);
    const std::vector<float> rFit = modelReflectionMap(fit.model, bins);
    if (reference) {
        if (reference->bins.toString() != bins.toString())
            throw InputError(reference->dir + ": reference bins " + reference->bins.toString() +
                             " differ from the fitted RDM's " + bins.toString());
        // Noise floor: the same metric between the two gathers.
        const std::vector<double> pT = modelTransmissionMap(fit.model, bins);
        double se = 0, n = 0, seFloor = 0;
        for (size_t i = 0; i < pT.size(); ++i) {
            const double w = static_cast<double>(reference->count[i]);
            se += w * (pT[i] - reference->pT[i]) * (pT[i] - reference->pT[i]);
            seFloor += w * (rdm.pT[i] - reference->pT[i]) * (rdm.pT[i] - reference->pT[i]);
            n += w;
        }
        const double mRef = coarseRelativeL2(mFit, reference->rdmM, bins);
        const double rRef = coarseRelativeL2(rFit, reference->rdmR, bins);
        const double mFloor = coarseRelativeL2(rdm.rdmM, reference->rdmM, bins);
        const double rFloor = coarseRelativeL2(rdm.rdmR, reference->rdmR, bins);
        // Error against the noise-free RDM: the reference's own noise adds
        // (in squares) half the squared distance between two gathers.
        auto againstTruth = [](double e, double floor) {
            return std::sqrt(std::max(0.0, e * e - 0.5 * floor * floor));
        };
        errors["reference"] = {
            {"rdm", reference->dir},
            {"t_rmse", std::sqrt(se / n)},
            {"m_rel_l2", mRef},
            {"r_rel_l2", rRef},
            {"noise_floor",
             {{"t_rmse", std::sqrt(seFloor / n)}, {"m_rel_l2", mFloor}, {"r_rel_l2", rFloor}}},
            {"estimated_against_noise_free_rdm",
             {{"m_rel_l2", againstTruth(mRef, mFloor)}, {"r_rel_l2", againstTruth(rRef, rFloor)}}}};
    }
    writeFileAtomic(out.path() + "/errors.json", errors.dump(2) + "\n");

    PlotOptions plot;
    plot.title = "training loss (mean over logging intervals)";
    plot.xLabel = "Adam step";
    plot.yLabel = "loss";
    const Image loss = plotLines({{"T net", r.tLoss.step, r.tLoss.loss, defaultPlotColor(0)},
                                  {"M net", r.mLoss.step, r.mLoss.loss, defaultPlotColor(1)}},
                                 plot);
    writePng(out.path() + "/loss.png", loss);

    writeSliceComparisons(out.path(), rdm, rFit, mFit);
    out.commit();
}

}  // namespace weft
