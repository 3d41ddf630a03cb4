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
#include "weft/core/math.h"
#include "weft/core/progress.h"
#include "weft/fit/colour_basis.h"
#include "weft/fit/family_calibration.h"
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

// The mean of a yarn's M targets over the training's cells
// (FamilyTrainingPoint::meanM) at kFamilyMeanNodes colours of `range`: with
// cells drawn with probability solidAngle(o) / (4 pi nIn), each M path adds
// W0 C^k / count(i) / (4 pi nIn).
std::array<std::vector<float>, 3> meanMTable(const std::vector<ColourPath>& paths,
                                             const std::vector<int64_t>& count,
                                             const ColourRange& range) {
    // h_c[k]: the paths' weights by their number of TT events.
    std::array<std::vector<double>, 3> h;
    const double norm = 1.0 / (4 * kPi * static_cast<double>(count.size()));
    for (const ColourPath& p : paths) {
        if (p.kind != ColourPath::M) continue;
        for (int c = 0; c < 3; ++c) {
            if (h[c].size() <= static_cast<size_t>(p.ttEvents)) h[c].resize(p.ttEvents + 1, 0.0);
            h[c][p.ttEvents] += p.weight[c] * norm / static_cast<double>(count[p.incidentBin]);
        }
    }
    std::array<std::vector<float>, 3> table;
    for (int c = 0; c < 3; ++c) {
        table[c].resize(kFamilyMeanNodes);
        for (int g = 0; g < kFamilyMeanNodes; ++g) {
            const double colour =
                range.lo + (range.hi - range.lo) * g / static_cast<double>(kFamilyMeanNodes - 1);
            double sum = 0, power = 1;
            for (double hk : h[c]) sum += hk * power, power *= colour;
            table[c][g] = static_cast<float>(sum);
        }
    }
    return table;
}

LoadedYarn loadYarn(const FamilyGather& gather, int k, bool keepR, bool keepPaths,
                    const ColourRange& range, FamilyTrainingPoint& point) {
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
    point.meanM = meanMTable(paths, counts.count, range);
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
        // The rows of this yarn are basis (x) features times eq. 8: their
        // normal equations are the yarn's 4 x 4 ones (x) f f^T.
        Eigen::Matrix4d yarnA = Eigen::Matrix4d::Zero();
        Eigen::Vector4d yarnB = Eigen::Vector4d::Zero();
        forEachMaskingRow(pe, pr, coarse, [&](double w, const auto& basis, double e, double r) {
            const Eigen::Vector4d v(basis[0] * e, basis[1] * e, basis[2] * e, basis[3] * e);
            yarnA += w * v * v.transpose();
            yarnB += w * r * v;
            targetSquares += w * r * r;
        });
        const Eigen::Map<const Eigen::Matrix<double, kFamilyMaskingFeatures, 1>> f(features.data());
        const Eigen::MatrixXd ff = f * f.transpose();
        for (int i = 0; i < kMaskingCoefficients; ++i) {
            b.segment<kFamilyMaskingFeatures>(i * kFamilyMaskingFeatures) += yarnB[i] * f;
            for (int j = 0; j < kMaskingCoefficients; ++j)
                a.block<kFamilyMaskingFeatures, kFamilyMaskingFeatures>(
                    i * kFamilyMaskingFeatures, j * kFamilyMaskingFeatures) += yarnA(i, j) * ff;
        }
    }
    const Eigen::VectorXd x = a.ldlt().solve(b);
    const double squares = x.dot(a * x) - 2 * x.dot(b) + targetSquares;
    *residual = targetSquares > 0 ? std::sqrt(std::max(squares, 0.0) / targetSquares) : 0.0;
    return std::vector<double>(x.data(), x.data() + n);
}

}  // namespace

FitConfig FamilyFitOptions::defaultConfig() {
    FitConfig config;
    config.t.hidden = {16, 16};
    config.m.hidden = {32, 32, 32};
    config.m.steps = 600000;
    config.calibrationDegree = kFamilyCalibrationDegree;
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
    const bool recalibrate = options.recalibrate.has_value();
    auto contains = [](const std::vector<size_t>& set, size_t k) {
        return std::find(set.begin(), set.end(), k) != set.end();
    };
    const std::vector<size_t> basisYarns =
        recalibrate ? std::vector<size_t>{} : spreadIndices(yarns, kFamilyBasisYarns);
    const std::vector<size_t> maskingYarns = config.masking && !recalibrate
                                                 ? spreadIndices(yarns, kFamilyMaskingYarns)
                                                 : std::vector<size_t>{};
    const std::vector<size_t> calibrationYarns = config.calibrationDegree >= 0
                                                     ? spreadIndices(yarns, kFamilyCalibrationYarns)
                                                     : std::vector<size_t>{};
    std::vector<FamilyTrainingPoint> points(yarns);
    std::vector<LoadedYarn> loaded(yarns);
    {
        // A recalibration reads the calibration's yarns only.
        const std::vector<size_t> read =
            recalibrate ? calibrationYarns : spreadIndices(yarns, yarns);
        Progress progress("read yarns", read.size(), quiet);
        for (size_t k : read) {
            const bool keepR = contains(maskingYarns, k) || contains(calibrationYarns, k);
            loaded[k] = loadYarn(gather, static_cast<int>(k), keepR, contains(basisYarns, k),
                                 options.range, points[k]);
            progress.add(1);
        }
        progress.finish();
    }
    nlohmann::json record;
    record["read_seconds"] = phaseDone("read the yarns");

    FamilyFitResult result;
    FamilyModel& model = result.model;
    if (recalibrate) {
        model = *options.recalibrate;
        if (model.box.toJson() != gather.options.box.toJson())
            throw InputError("--recalibrate: the model's box is not the family gather's (" +
                             gather.dir +
                             "/family.json): recalibrate a model with the gather it "
                             "was fitted to");
        record = model.fit;
        record["recalibrated"] = true;
    } else {
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
                pooled.insert(pooled.end(), loaded[k].basisPaths.begin(),
                              loaded[k].basisPaths.end());
                for (size_t i = 0; i < count.size(); ++i) count[i] += loaded[k].count[i];
                loaded[k].basisPaths = {};
            }
            ColourBasisFit basis;
            arena.execute([&] {
                basis = fitColourBasis(pooled, bins, count, options.range, options.functions);
            });
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
        model.mNet = fitFamilyMNetwork(points, model.colour, config, options.seed, arena, quiet,
                                       &result.mLoss);
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
    }

    // 5. The energy calibration.
    model.calibration = {};
    if (!calibrationYarns.empty()) {
        std::vector<FamilyCalibrationYarn> data;
        for (size_t k : calibrationYarns)
            data.push_back(
                {gather.points[k], loaded[k].r.get(), loaded[k].m.get(), &loaded[k].count});
        nlohmann::json summary;
        model.calibration = fitFamilyCalibration(model, data, bins, config.calibrationDegree,
                                                 options.calibrateM, threads, quiet, &summary);
        summary["seconds"] = phaseDone("energy calibration");
        record["calibration"] = summary;
    } else {
        record["calibration"] = nullptr;
    }

    // 6. The sampling lobe at the box's centre.
    if (!recalibrate) {
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

    if (recalibrate) {
        record["recalibration_seconds"] = secondsSince(t0);
        record["config"]["energy_calibration_degree"] = config.calibrationDegree;
        model.fit = record;
        model.validate();
        return result;
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
