// Fitting a family model (family_fit.h).
#include "weft/fit/family_fit.h"

#include <tbb/task_arena.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/progress.h"
#include "weft/fit/colour_basis.h"
#include "weft/fit/masking_fit.h"
#include "weft/fit/metrics.h"
#include "weft/fit/model_maps.h"
#include "weft/gather/colour_paths.h"
#include "weft/gather/gather_folder.h"
#include "weft/yarn/yarn_lobes.h"

namespace weft {

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

// `count` indices spread evenly over [0, total).
std::vector<size_t> spreadIndices(size_t total, size_t count) {
    std::vector<size_t> indices;
    count = std::min(count, total);
    for (size_t k = 0; k < count; ++k) indices.push_back(k * total / count);
    return indices;
}

// One yarn's gathered data, read from its folder.
struct LoadedYarn {
    std::unique_ptr<ColourTargets> m, r;  // r only for the masking yarns
    std::vector<ColourPath> basisPaths;   // only for the colour-function yarns
    std::vector<int64_t> count;
};

LoadedYarn loadYarn(const FamilyGather& gather, int k, bool keepR, bool keepPaths,
                    FamilyTrainingPoint& point) {
    const GatherFolder folder = readGatherFolder(gather.pointDir(k), GatherFolderKind::Gather);
    const RdmBins& bins = gather.options.bins;  // loadFamilyGather checked each yarn's
    const GatherCounts counts = readGatherCounts(folder);
    std::vector<ColourPath> paths = readColourPaths(folder, counts);
    LoadedYarn yarn;
    yarn.count = counts.count;
    point.incidentCdf.resize(counts.count.size());
    point.pT.resize(counts.count.size());
    double sum = 0;
    for (size_t i = 0; i < counts.count.size(); ++i) {
        point.incidentCdf[i] = sum += static_cast<double>(counts.count[i]);
        point.pT[i] = counts.count[i] > 0 ? static_cast<double>(counts.countT[i]) /
                                                static_cast<double>(counts.count[i])
                                          : 0.0;
    }
    if (sum <= 0) throw InputError(folder.dir + ": the yarn's gather has no paths");
    const auto q = gather.options.box.normalised(gather.points[k]);
    for (int d = 0; d < FamilyBox::kDimensions; ++d) point.inputs[d] = static_cast<float>(q[d]);
    yarn.m = std::make_unique<ColourTargets>(paths, bins, counts.count, ColourPath::M,
                                             ColourTargets::CellIndex::Sparse);
    point.m = yarn.m.get();
    if (keepR)
        yarn.r = std::make_unique<ColourTargets>(paths, bins, counts.count, ColourPath::R,
                                                 ColourTargets::CellIndex::Sparse);
    if (keepPaths) yarn.basisPaths = std::move(paths);
    return yarn;
}

// Step 4: masking coefficients linear in the yarn's parameters
// (family_model.h), by least squares over the yarns of `maskingYarns`:
// minimise sum W_O (m(mu_I, mu_O; p) P_eq8(p) - P_rdm(p))^2 over the coarse
// grid, channels and yarns. `residual` receives the relative L2 of the fit.
std::vector<double> fitFamilyMasking(const FamilyModel& family, const FamilyGather& gather,
                                     const std::vector<size_t>& maskingYarns,
                                     const std::vector<LoadedYarn>& loaded, tbb::task_arena& arena,
                                     double* residual) {
    constexpr int n = kMaskingCoefficients * kFamilyMaskingFeatures;
    const RdmBins& fine = gather.options.bins;
    const RdmBins& coarse = kCoarseErrorBins;
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
    Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
    double targetSquares = 0;
    for (size_t k : maskingYarns) {
        const YarnPoint& p = gather.points[k];
        const YarnModel plain = family.at(p, "family fit");  // no masking yet
        std::vector<float> eq8;
        arena.execute([&] { eq8 = modelReflectionMap(plain, fine); });
        const std::vector<double> pe = poolRdm(eq8, fine, coarse),
                                  pr = poolRdm(loaded[k].r->map(Rgb(0.5)), fine, coarse);
        const auto features = familyMaskingFeatures(family.box, p);
        Eigen::VectorXd v(n);
        forEachMaskingRow(pe, pr, coarse, [&](double w, const auto& basis, double e, double r) {
            for (int j = 0; j < kMaskingCoefficients; ++j)
                for (int l = 0; l < kFamilyMaskingFeatures; ++l)
                    v[j * kFamilyMaskingFeatures + l] = basis[j] * features[l] * e;
            a.selfadjointView<Eigen::Lower>().rankUpdate(v, w);
            b += w * r * v;
            targetSquares += w * r * r;
        });
    }
    const Eigen::MatrixXd full = a.selfadjointView<Eigen::Lower>();
    const Eigen::VectorXd x = full.ldlt().solve(b);
    const double squares = x.dot(full * x) - 2 * x.dot(b) + targetSquares;
    *residual = targetSquares > 0 ? std::sqrt(std::max(squares, 0.0) / targetSquares) : 0.0;
    return std::vector<double>(x.data(), x.data() + n);
}

}  // namespace

FitConfig FamilyFitOptions::defaultConfig() {
    FitConfig config;
    config.t.hidden = {16, 16};
    config.m.steps = 300000;
    config.calibrationDegree = -1;
    return config;
}

FamilyFitResult fitFamilyModel(const FamilyGather& gather, const FamilyFitOptions& options) {
    const FitConfig& config = options.config;
    config.validate("fit configuration");
    options.range.validate("--colour-range");
    if (options.functions < 2 || options.functions > ColourBasis::kMaxFunctions)
        throw InputError("--colour-functions " + std::to_string(options.functions) +
                         " is out of range: allowed [2, " +
                         std::to_string(ColourBasis::kMaxFunctions) + "]");
    if (config.calibrationDegree >= 0)
        throw InputError(
            "fit configuration: energy_calibration_degree must be -1 for a family fit (a family "
            "model has no energy calibration; docs/family.md)");
    const auto t0 = Clock::now();
    const bool quiet = options.quiet;
    const int threads =
        config.threads > 0 ? config.threads : tbb::this_task_arena::max_concurrency();
    tbb::task_arena arena(threads);
    const RdmBins& bins = gather.options.bins;
    const size_t yarns = gather.points.size();
    auto phase = Clock::now();
    auto phaseDone = [&](const char* what) {
        const double s = secondsSince(phase);
        if (!quiet) std::fprintf(stderr, "fit family: %s in %.1fs\n", what, s);
        phase = Clock::now();
        return s;
    };

    // The yarns' data.
    const std::vector<size_t> basisYarns = spreadIndices(yarns, kFamilyBasisYarns);
    const std::vector<size_t> maskingYarns =
        config.masking ? spreadIndices(yarns, kFamilyMaskingYarns) : std::vector<size_t>{};
    std::vector<FamilyTrainingPoint> points(yarns);
    std::vector<LoadedYarn> loaded(yarns);
    {
        Progress progress("read yarns", yarns, quiet);
        for (size_t k = 0; k < yarns; ++k) {
            const bool keepR =
                std::find(maskingYarns.begin(), maskingYarns.end(), k) != maskingYarns.end();
            const bool keepPaths =
                std::find(basisYarns.begin(), basisYarns.end(), k) != basisYarns.end();
            loaded[k] = loadYarn(gather, static_cast<int>(k), keepR, keepPaths, points[k]);
            progress.add(1);
        }
        progress.finish();
    }
    nlohmann::json record;
    record["read_seconds"] = phaseDone("read the yarns");

    FamilyFitResult result;
    FamilyModel& model = result.model;
    model.box = gather.options.box;
    // 1. T.
    double tRmse = 0;
    model.tNet = fitFamilyTransmissionNetwork(points, bins, config, options.seed, arena, quiet,
                                              &result.tLoss, &tRmse);
    record["t_rmse"] = tRmse;
    record["t_seconds"] = phaseDone("T network");

    // 2. The colour functions from the pooled records of the basis yarns.
    {
        std::vector<ColourPath> pooled;
        std::vector<int64_t> count(bins.incidentCount(), 0);
        for (size_t k : basisYarns) {
            pooled.insert(pooled.end(), loaded[k].basisPaths.begin(), loaded[k].basisPaths.end());
            for (size_t i = 0; i < count.size(); ++i) count[i] += loaded[k].count[i];
            loaded[k].basisPaths = {};
        }
        ColourBasisFit basis;
        arena.execute(
            [&] { basis = fitColourBasis(pooled, bins, count, options.range, options.functions); });
        model.colour = basis.basis;
        record["colour"] = {{"functions", options.functions},
                            {"c_tt_range", {options.range.lo, options.range.hi}},
                            {"basis_yarns", basisYarns.size()},
                            {"basis_error_mean", basis.meanError},
                            {"basis_error_worst", basis.worstError}};
        phaseDone("colour functions");
    }

    // 3. M.
    phase = Clock::now();
    model.mNet =
        fitFamilyMNetwork(points, model.colour, config, options.seed, arena, quiet, &result.mLoss);
    const double mSeconds = phaseDone("M network");
    record["m_seconds"] = mSeconds;
    record["m_samples_per_second"] =
        static_cast<double>(config.m.steps) * config.m.batch / std::max(mSeconds, 1e-9);

    // 4. Masking.
    if (config.masking) {
        double residual = 0;
        model.masking = fitFamilyMasking(model, gather, maskingYarns, loaded, arena, &residual);
        record["masking"] = {{"yarns", maskingYarns.size()}, {"r_rel_l2", residual}};
        phaseDone("R masking term");
    }

    // 5. The sampling lobe at the box's centre.
    {
        const YarnModel centre =
            model.at(model.centre(), "family fit").forColour(Rgb(0.5), "family fit");
        std::vector<float> rMap, mMap;
        arena.execute([&] {
            rMap = modelReflectionMap(centre, bins);
            mMap = modelMultipleScatteringMap(centre, bins);
        });
        const double rEnergy = mapEnergy(rMap, bins), mEnergy = mapEnergy(mMap, bins);
        const double kappaR = rEnergy + mEnergy > 0 ? rEnergy / (rEnergy + mEnergy) : 0.5;
        double secondMoment = 0;
        model.sampling = fitSamplingLobe(centre, mMap, bins, kappaR, &secondMoment, threads);
        record["m_second_moment"] = secondMoment;
        phaseDone("sampling lobe");
    }

    record["seconds"] = secondsSince(t0);
    record["seed"] = options.seed;
    record["config"] = config.toJson();
    record["gather"] = {{"path", recordedPath(gather.dir)},
                        {"yarns", yarns},
                        {"paths_per_yarn", gather.options.pathsPerPoint},
                        {"seed", gather.options.seed}};
    model.fit = record;
    model.validate();
    return result;
}

}  // namespace weft
