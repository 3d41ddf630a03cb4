#include "weft/fit/family_calibration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "weft/core/test_util.h"
#include "weft/fit/calibration.h"
#include "weft/fit/family_fit.h"
#include "weft/fit/metrics.h"
#include "weft/gather/colour_paths.h"
#include "weft/gather/gather_folder.h"
#include "weft/yarn/yarn_bsdf.h"
#include "weft/yarn/yarn_integrals.h"

namespace weft {
namespace {

// Synthetic systems with a known scale: energies E in [0.02, 0.3], the RDM's
// y the mean of n = 30 paths whose weights are w = 0.5 each (y = w K / n, K
// Poisson with mean n mu / w, so E[y] = mu = E s; K about 10): the few-path
// bins of a family yarn. The Poisson fit recovers log s without bias; least squares
// on log(y / E) (bins with y > 0, as a one-yarn calibration fits them) is
// biased low by about 1 / (2 E[K]) and more where bins with K = 0 drop out.
TEST(FamilyCalibration, PoissonFitIsUnbiasedWhereLogRatiosAreNot) {
    const RdmBins bins{6, 12, 1, 1};
    const int degree = 2, terms = EnergyCalibration::termCount(degree);
    Eigen::MatrixXd basis(static_cast<Eigen::Index>(bins.incidentCount()), terms);
    for (size_t i = 0; i < bins.incidentCount(); ++i) {
        std::vector<double> row(static_cast<size_t>(terms));
        EnergyCalibration::basis(bins.incidentCentre(i), degree, row.data());
        for (int k = 0; k < terms; ++k) basis(static_cast<Eigen::Index>(i), k) = row[k];
    }
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::vector<CalibrationFeatures> features(120);
    for (CalibrationFeatures& f : features) {
        f[0] = 1;
        for (int l = 1; l < kFamilyCalibrationFeatures; ++l) f[l] = 2 * uniform(rng) - 1;
    }
    // The truth: log s = 0.3 + 0.2 q_1 - 0.25 z + 0.15 x q_7 (z, x: wi's components).
    std::vector<double> truth(static_cast<size_t>(terms * kFamilyCalibrationFeatures), 0.0);
    truth[EnergyCalibration::termIndex(0, 0, 0, degree) * kFamilyCalibrationFeatures + 0] = 0.3;
    truth[EnergyCalibration::termIndex(0, 0, 0, degree) * kFamilyCalibrationFeatures + 1] = 0.2;
    truth[EnergyCalibration::termIndex(0, 0, 1, degree) * kFamilyCalibrationFeatures + 0] = -0.25;
    truth[EnergyCalibration::termIndex(1, 0, 0, degree) * kFamilyCalibrationFeatures + 7] = 0.15;
    auto logScale = [&](const std::vector<double>& beta, size_t bin, size_t group) {
        double eta = 0;
        for (int k = 0; k < terms; ++k)
            for (int l = 0; l < kFamilyCalibrationFeatures; ++l)
                eta += beta[k * kFamilyCalibrationFeatures + l] *
                       basis(static_cast<Eigen::Index>(bin), k) * features[group][l];
        return eta;
    };
    const double n = 30, w = 0.5;
    std::vector<FamilyCalibrationPoint> points;
    for (size_t g = 0; g < features.size(); ++g)
        for (size_t i = 0; i < bins.incidentCount(); ++i) {
            const double e = 0.02 + 0.28 * uniform(rng);
            const double mu = e * std::exp(logScale(truth, i, g));
            std::poisson_distribution<int> paths(n * mu / w);
            points.push_back(
                {static_cast<int32_t>(i), static_cast<int32_t>(g), n, e, w * paths(rng) / n});
        }
    const PoissonFit fit = fitPoissonLogLinear(points, basis, features);
    EXPECT_LT(fit.errorAfter, fit.errorBefore);

    // The log-ratio least squares on the same points, for comparison.
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(terms * kFamilyCalibrationFeatures,
                                              terms * kFamilyCalibrationFeatures);
    Eigen::VectorXd b = Eigen::VectorXd::Zero(terms * kFamilyCalibrationFeatures);
    for (const FamilyCalibrationPoint& p : points) {
        if (!(p.rdm > 0)) continue;
        Eigen::VectorXd x(terms * kFamilyCalibrationFeatures);
        for (int k = 0; k < terms; ++k)
            for (int l = 0; l < kFamilyCalibrationFeatures; ++l)
                x[k * kFamilyCalibrationFeatures + l] =
                    basis(p.bin, k) * features[static_cast<size_t>(p.group)][l];
        const double weight = p.paths * p.model;
        a += weight * x * x.transpose();
        b += weight * std::log(p.rdm / p.model) * x;
    }
    const Eigen::VectorXd logFit = a.ldlt().solve(b);
    const std::vector<double> logBeta(logFit.data(), logFit.data() + logFit.size());

    double poissonBias = 0, logBias = 0, poissonSpread = 0;
    for (const FamilyCalibrationPoint& p : points) {
        const double t = logScale(truth, static_cast<size_t>(p.bin), static_cast<size_t>(p.group));
        const double e =
            logScale(fit.beta, static_cast<size_t>(p.bin), static_cast<size_t>(p.group)) - t;
        poissonBias += e;
        poissonSpread += e * e;
        logBias += logScale(logBeta, static_cast<size_t>(p.bin), static_cast<size_t>(p.group)) - t;
    }
    const double count = static_cast<double>(points.size());
    std::printf("mean error of log s: Poisson %.4f (rms %.4f), log least squares %.4f\n",
                poissonBias / count, std::sqrt(poissonSpread / count), logBias / count);
    EXPECT_LT(std::fabs(poissonBias / count), 0.01);
    EXPECT_LT(std::sqrt(poissonSpread / count), 0.05);
    EXPECT_LT(logBias / count, -0.03);  // what the Poisson fit is there to avoid
}

class FamilyCalibrationFit : public testing::TempDirTest {};

// A small family fitted with its calibration: the calibrated yarns, as the
// renderer evaluates them (YarnBsdf, integrateDirections: not the fit's own
// evaluation), hold in total the energy of the yarns' RDMs (recoloured from
// their folders) for R and for M at every node colour. The Poisson fit's
// score equation for the constant term says exactly that (clamping aside);
// an error in the features, the basis, the node colours or the way at()
// applies the coefficients breaks it. Uncalibrated, the totals differ.
TEST_F(FamilyCalibrationFit, CalibratedYarnsHoldTheirRdmsEnergy) {
    FamilyGatherOptions g;
    g.box.fibers = {250, 350};
    g.box.density = {0.25, 0.35};
    g.box.betaRDeg = {5, 8};
    g.points = 3;
    g.pathsPerPoint = testing::scaled(20000);
    g.bins = {3, 8, 6, 12};
    g.seed = 5;
    g.threads = 2;
    g.quiet = true;
    gatherFamily(g, path("family"));
    const FamilyGather gather = loadFamilyGather(path("family"));
    FamilyFitOptions o;
    o.config.t.steps = 400;
    o.config.t.restarts = 1;
    o.config.m.steps = 4000;  // an M network near its targets: scales within the clamp
    o.config.m.hidden = {8, 8};
    o.config.threads = 2;
    o.config.calibrationDegree = 1;
    o.functions = 3;
    o.calibrateM = true;
    o.quiet = true;
    const FamilyModel model = fitFamilyModel(gather, o).model;
    ASSERT_EQ(model.calibration.degree, 1);
    FamilyModel plain = model;
    plain.calibration = {};

    const RdmBins& bins = g.bins;
    const std::vector<double> nodes = model.calibration.cTT;
    for (size_t s = 0; s <= nodes.size(); ++s) {
        const double grey = s == 0 ? 0.5 : nodes[s - 1];
        double calibrated = 0, uncalibrated = 0, rdm = 0;
        for (int k = 0; k < g.points; ++k) {
            RecolouredGather recoloured = recolourGather(gather.pointDir(k), Rgb(grey));
            const GatherResult result =
                normaliseGather(std::move(recoloured.sums), recoloured.options);
            const std::vector<Rgb> target =
                incidentEnergies(s == 0 ? result.rdmR : result.rdmM, bins);
            const YarnBsdf withCal(model.at(gather.points[k], "yarn").forColour(Rgb(grey), "yarn"),
                                   "yarn", YarnBsdfOptions{false, YarnSampling::Fitted});
            const YarnBsdf without(plain.at(gather.points[k], "yarn").forColour(Rgb(grey), "yarn"),
                                   "yarn", YarnBsdfOptions{false, YarnSampling::Fitted});
            for (size_t i = 0; i < bins.incidentCount(); ++i) {
                const double n = static_cast<double>(result.count[i]);
                if (result.count[i] < kFamilyCalibrationMinPaths) continue;
                const Vec3 wi = bins.incidentCentre(i);
                const DirectionalIntegrals a = integrateDirections(withCal, wi, 1, false);
                const DirectionalIntegrals b = integrateDirections(without, wi, 1, false);
                for (int c = 0; c < 3; ++c) {
                    calibrated += n * (s == 0 ? a.r[c] : a.m[c]);
                    uncalibrated += n * (s == 0 ? b.r[c] : b.m[c]);
                    rdm += n * target[i][c];
                }
            }
        }
        std::printf("%s at C_TT %.3f: RDM %.5g, calibrated %.5g, uncalibrated %.5g\n",
                    s == 0 ? "R" : "M", grey, rdm, calibrated, uncalibrated);
        EXPECT_NEAR(calibrated / rdm, 1.0, 0.01) << (s == 0 ? "R" : "M") << " at " << grey;
    }
}

}  // namespace
}  // namespace weft
