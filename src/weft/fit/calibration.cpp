// Step 4 of the fit (calibration.h): the energy calibration's least squares.
#include "weft/fit/calibration.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "weft/core/json_message.h"
#include "weft/core/math.h"
#include "weft/fit/colour_targets.h"
#include "weft/fit/metrics.h"
#include "weft/fit/model_maps.h"
#include "weft/yarn/yarn_bsdf.h"
#include "weft/yarn/yarn_integrals.h"

namespace weft {

namespace {

// Model energies of R and M (integrals over wo of the yarn BSDF without
// calibration or energy guard, yarn_integrals.h) and the RDM's (metrics.h) for
// every incident bin with enough paths.
struct BinEnergies {
    std::vector<size_t> bin;
    std::vector<Rgb> modelR, modelM, rdmR, rdmM;
    std::vector<double> pT;  // P(T) of the model at every incident bin centre
};

BinEnergies binEnergies(const YarnModel& fitted, const RdmData& rdm, int64_t minPaths,
                        tbb::task_arena& arena) {
    const RdmBins& bins = rdm.bins;
    YarnModel model = fitted;
    model.calibration = EnergyCalibration{};
    const YarnBsdf bsdf(model, "the model being calibrated", YarnBsdfOptions{false, YarnSampling::Fitted});
    BinEnergies e;
    for (size_t i = 0; i < bins.incidentCount(); ++i)
        if (rdm.count[i] >= minPaths) e.bin.push_back(i);
    const size_t n = e.bin.size();
    e.modelR.resize(n), e.modelM.resize(n);
    e.pT = modelTransmissionMap(model, bins);
    const std::vector<Rgb> rdmR = incidentEnergies(rdm.rdmR, bins);
    const std::vector<Rgb> rdmM = incidentEnergies(rdm.rdmM, bins);
    for (size_t k = 0; k < n; ++k) e.rdmR.push_back(rdmR[e.bin[k]]), e.rdmM.push_back(rdmM[e.bin[k]]);
    arena.execute([&] {
        tbb::parallel_for(size_t(0), n, [&](size_t k) {
            const DirectionalIntegrals d =
                integrateDirections(bsdf, bins.incidentCentre(e.bin[k]), 1, false);
            e.modelR[k] = d.r, e.modelM[k] = d.m;
        });
    });
    return e;
}

}  // namespace

EnergyCalibration fitEnergyCalibration(const YarnModel& model, const RdmData& rdm, int degree,
                                       int threads, nlohmann::json* summary) {
    tbb::task_arena arena(threads > 0 ? threads : tbb::this_task_arena::max_concurrency());
    const BinEnergies e = binEnergies(model, rdm, kCalibrationMinPaths, arena);
    // Enough bins for a stable fit: at least 4 per coefficient.
    const int bins = static_cast<int>(e.bin.size());
    while (degree >= 0 && 4 * EnergyCalibration::termCount(degree) > bins) --degree;
    EnergyCalibration cal;
    cal.degree = degree;
    std::vector<Vec3> wi(e.bin.size());
    for (size_t k = 0; k < e.bin.size(); ++k) wi[k] = rdm.bins.incidentCentre(e.bin[k]);
    // Per component and channel, the degree (or none) is chosen by two-fold
    // cross-validation on interleaved bins: a noisy RDM (few paths per bin,
    // or a dark channel) gets a low degree or no calibration at all instead
    // of a polynomial fitted to its noise. Weights: path count times the
    // model's energy, about the number of paths behind the bin's energy
    // (whose inverse is the variance of its logarithm); the RDM's own energy
    // would favour bins that fluctuated up.
    std::array<std::array<int, 3>, 2> chosen{};
    auto fitChannel = [&](const std::vector<Rgb>& modelE, const std::vector<Rgb>& rdmE, int c,
                          int* chosenDegree) {
        std::vector<Vec3> x[2];
        std::vector<double> y[2], w[2];
        for (size_t k = 0; k < e.bin.size(); ++k)
            if (modelE[k][c] > 0 && rdmE[k][c] > 0) {
                const int half = static_cast<int>(k % 2);
                x[half].push_back(wi[k]);
                y[half].push_back(std::log(rdmE[k][c] / modelE[k][c]));
                w[half].push_back(static_cast<double>(rdm.count[e.bin[k]]) * modelE[k][c]);
            }
        auto heldOutError = [&](int d) {
            double error = 0;
            for (int half = 0; half < 2; ++half) {
                const int other = 1 - half;
                std::vector<double> coefficients;
                if (d >= 0) {
                    if (static_cast<int>(x[half].size()) < 4 * EnergyCalibration::termCount(d))
                        return std::numeric_limits<double>::infinity();
                    coefficients = fitLogPolynomial(x[half], y[half], w[half], d);
                }
                std::vector<double> f(static_cast<size_t>(EnergyCalibration::termCount(std::max(d, 0))));
                for (size_t k = 0; k < x[other].size(); ++k) {
                    double predicted = 0;
                    if (d >= 0) {
                        EnergyCalibration::basis(x[other][k], d, f.data());
                        for (size_t q = 0; q < f.size(); ++q) predicted += coefficients[q] * f[q];
                        predicted = std::clamp(predicted, -EnergyCalibration::kMaxLogScale,
                                               EnergyCalibration::kMaxLogScale);
                    }
                    error += w[other][k] * sqr(predicted - y[other][k]);
                }
            }
            return error;
        };
        int best = -1;
        double bestError = heldOutError(-1);
        for (int d = 0; d <= degree; ++d) {
            const double err = heldOutError(d);
            if (err < bestError) best = d, bestError = err;
        }
        *chosenDegree = best;
        std::vector<double> full(static_cast<size_t>(EnergyCalibration::termCount(degree)), 0.0);
        if (best < 0) return full;
        std::vector<Vec3> xs = x[0];
        std::vector<double> ys = y[0], ws = w[0];
        xs.insert(xs.end(), x[1].begin(), x[1].end());
        ys.insert(ys.end(), y[1].begin(), y[1].end());
        ws.insert(ws.end(), w[1].begin(), w[1].end());
        const std::vector<double> low = fitLogPolynomial(xs, ys, ws, best);
        // The degree-`best` basis is a subset of the degree-`degree` one.
        size_t n = 0;
        for (int a = 0; a <= std::min(1, best); ++a)
            for (int b = 0; b <= best - a; ++b)
                for (int q = 0; q <= best - a - b; ++q)
                    full[static_cast<size_t>(EnergyCalibration::termIndex(a, b, q, degree))] = low[n++];
        return full;
    };
    if (degree >= 0)
        for (int c = 0; c < 3; ++c) {
            cal.r[c] = fitChannel(e.modelR, e.rdmR, c, &chosen[0][c]);
            cal.m[c] = fitChannel(e.modelM, e.rdmM, c, &chosen[1][c]);
        }

    if (summary) {
        // Albedo (T + R + M at the bin centres, T from the network for both,
        // so that only the calibrated parts differ) against the RDM's, before and after.
        Rgb before, after, rScaleMin(1e9), rScaleMax(0.0), mScaleMin(1e9), mScaleMax(0.0);
        size_t within = 0;
        const std::vector<double>& pT = e.pT;
        for (size_t k = 0; k < e.bin.size(); ++k) {
            const size_t i = e.bin[k];
            const EnergyCalibration::Scales s =
                degree >= 0 ? cal.scales(wi[k]) : EnergyCalibration::Scales{};
            const Rgb target = e.rdmR[k] + e.rdmM[k] + Rgb(rdm.pT[i]);
            const Rgb raw = e.modelR[k] + e.modelM[k] + Rgb(pT[i]);
            const Rgb scaled = e.modelR[k] * s.r + e.modelM[k] * s.m + Rgb(pT[i]);
            for (int c = 0; c < 3; ++c) {
                if (!(target[c] > 0)) continue;
                before[c] += std::fabs(raw[c] / target[c] - 1);
                after[c] += std::fabs(scaled[c] / target[c] - 1);
                within += std::fabs(scaled[c] / target[c] - 1) <= 0.03;
                rScaleMin[c] = std::min(rScaleMin[c], s.r[c]), rScaleMax[c] = std::max(rScaleMax[c], s.r[c]);
                mScaleMin[c] = std::min(mScaleMin[c], s.m[c]), mScaleMax[c] = std::max(mScaleMax[c], s.m[c]);
            }
        }
        const double n = std::max<double>(1.0, static_cast<double>(e.bin.size()));
                *summary = {{"degree", degree},
                    {"degrees_chosen", {{"r", chosen[0]}, {"m", chosen[1]}}},
                    {"bins", e.bin.size()},
                    {"min_paths", kCalibrationMinPaths},
                    {"albedo_rel_error_mean_abs_before", rgbJson(before / n)},
                    {"albedo_rel_error_mean_abs_after", rgbJson(after / n)},
                    {"albedo_within_3_percent_after", static_cast<double>(within) / (3 * n)},
                    {"r_scale_range", {rgbJson(rScaleMin), rgbJson(rScaleMax)}},
                    {"m_scale_range", {rgbJson(mScaleMin), rgbJson(mScaleMax)}}};
    }
    return cal;
}

std::vector<double> colourCalibrationNodes(const ColourRange& range) {
    // From the dark end (u large) to the light one, so that C_TT increases.
    const double uDark = ColourCalibration::variableOf(range.lo);
    const double uLight = ColourCalibration::variableOf(range.hi);
    std::vector<double> nodes;
    for (int g = 0; g < kColourCalibrationNodes; ++g) {
        const double u = uDark + (uLight - uDark) * g / (kColourCalibrationNodes - 1);
        nodes.push_back(g == 0                             ? range.lo
                        : g + 1 == kColourCalibrationNodes ? range.hi
                                                           : std::exp(-u * u));
    }
    return nodes;
}

ColourCalibration fitColourCalibration(const YarnModel& model, const RdmData& rdm,
                                       const std::vector<ColourPath>& paths, int degree,
                                       int threads, nlohmann::json* summary) {
    if (!model.colour) throw std::logic_error("fitColourCalibration: the model is not conditioned");
    const ColourRange& range = model.colour->range();
    const ColourTargets targetR(paths, rdm.bins, rdm.count, ColourPath::R);
    const ColourTargets targetM(paths, rdm.bins, rdm.count, ColourPath::M);
    YarnModel conditioned = model;
    conditioned.colourCalibration = {};
    ColourCalibration result;
    if (summary) *summary = nlohmann::json::array();
    for (const double grey : colourCalibrationNodes(range)) {
        RdmData recoloured;
        recoloured.dir = rdm.dir + " recoloured to C_TT " + formatNumber(grey);
        recoloured.bins = rdm.bins;
        recoloured.count = rdm.count;
        recoloured.pT = rdm.pT;
        recoloured.rdmR = targetR.map(Rgb(grey));
        recoloured.rdmM = targetM.map(Rgb(grey));
        nlohmann::json node;
        result.cTT.push_back(grey);
        result.nodes.push_back(fitEnergyCalibration(conditioned.forColour(Rgb(grey), "calibration"),
                                                    recoloured, degree, threads,
                                                    summary ? &node : nullptr));
        if (summary) {
            node["c_tt"] = grey;
            summary->push_back(node);
        }
    }
    return result;
}

std::vector<double> fitLogPolynomial(const std::vector<Vec3>& wi,
                                     const std::vector<double>& logRatio,
                                     const std::vector<double>& weight, int degree) {
    const int n = EnergyCalibration::termCount(degree);
    Eigen::MatrixXd a(static_cast<Eigen::Index>(wi.size()), n);
    Eigen::VectorXd b(static_cast<Eigen::Index>(wi.size()));
    double f[EnergyCalibration::termCount(EnergyCalibration::kMaxDegree)];
    for (size_t i = 0; i < wi.size(); ++i) {
        const double s = std::sqrt(weight[i]);
        EnergyCalibration::basis(wi[i], degree, f);
        for (int k = 0; k < n; ++k) a(static_cast<Eigen::Index>(i), k) = s * f[k];
        b(static_cast<Eigen::Index>(i)) = s * logRatio[i];
    }
    const Eigen::VectorXd c = a.colPivHouseholderQr().solve(b);
    return std::vector<double>(c.data(), c.data() + n);
}

}  // namespace weft
