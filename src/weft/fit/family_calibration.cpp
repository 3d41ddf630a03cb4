// The family model's energy calibration (family_calibration.h).
#include "weft/fit/family_calibration.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "weft/core/math.h"
#include "weft/core/progress.h"
#include "weft/fit/calibration.h"
#include "weft/fit/metrics.h"
#include "weft/fit/mlp.h"
#include "weft/yarn/sphere_rule.h"
#include "weft/yarn/yarn_evaluator.h"

namespace weft {

namespace {

constexpr int kFeatures = kFamilyCalibrationFeatures;
constexpr int kNewtonIterations = 30;

// The energies of one yarn at its incident bins with enough paths: R (any
// colour) and M at every node colour, of the model and of the RDM.
struct YarnEnergies {
    std::vector<int32_t> bin;
    std::vector<double> paths;
    std::vector<Rgb> modelR, rdmR;
    std::vector<std::vector<Rgb>> modelM, rdmM;  // [node][k]
};

YarnEnergies yarnEnergies(const FamilyModel& family, const FamilyCalibrationYarn& yarn,
                          const RdmBins& bins, const std::vector<double>& nodes) {
    const YarnModel conditioned = family.at(yarn.point, "family calibration");
    const YarnModel grey = conditioned.forColour(Rgb(0.5), "family calibration");
    const YarnEvaluator evaluator(grey, "family calibration", false);
    // S_M of the colour C at (wi, wo): exp(sum_j a_jc(wi, wo) phi_j(C))
    // (colour_basis.h) with a from the network's 3K outputs.
    const Mlp<float> coefficients(conditioned.mNet);
    const ColourBasis& basis = *conditioned.colour;
    const int functions = basis.functions();
    Eigen::MatrixXf phi(static_cast<Eigen::Index>(nodes.size()), functions);
    for (size_t g = 0; g < nodes.size(); ++g) {
        std::vector<double> values(static_cast<size_t>(functions));
        basis.eval(nodes[g], values.data());
        for (int j = 0; j < functions; ++j)
            phi(static_cast<Eigen::Index>(g), j) = static_cast<float>(values[j]);
    }
    const double betaR = radians(grey.fiber.betaRDeg);

    YarnEnergies e;
    const std::vector<Rgb> rdmR = incidentEnergies(yarn.r->map(Rgb(0.5)), bins);
    std::vector<std::vector<Rgb>> rdmM;
    for (double c : nodes) rdmM.push_back(incidentEnergies(yarn.m->map(Rgb(c)), bins));
    e.modelM.resize(nodes.size()), e.rdmM.resize(nodes.size());
    for (size_t i = 0; i < bins.incidentCount(); ++i) {
        const int64_t n = (*yarn.count)[i];
        if (n < kFamilyCalibrationMinPaths) continue;
        const Vec3 wi = bins.incidentCentre(i);
        const SphereRule rule = surfaceFiberSphereRule(evaluator.frame(), betaR, wi);
        const YarnIncident in = evaluator.incident(wi);
        const Eigen::Index count = static_cast<Eigen::Index>(rule.directions.size());
        Rgb r;
        Mlp<float>::Matrix x(6, count);
        Eigen::VectorXf w(count);
        for (Eigen::Index k = 0; k < count; ++k) {
            const Vec3& wo = rule.directions[static_cast<size_t>(k)];
            w[k] = static_cast<float>(rule.weights[static_cast<size_t>(k)]);
            if (evaluator.hasReflection())
                r += evaluator.rLobe().eval(in.wi, wo, in.fiber, evaluator.outAngles(wo), in.pT) *
                     rule.weights[static_cast<size_t>(k)];
            setInputColumn(x, k, wi, wo);
        }
        // 3K x count, a_jc at row 3 j + c (not needed without M nodes)
        const Eigen::MatrixXf a = nodes.empty() ? Eigen::MatrixXf() : coefficients.forward(x);
        e.bin.push_back(static_cast<int32_t>(i));
        e.paths.push_back(static_cast<double>(n));
        e.modelR.push_back(r);
        e.rdmR.push_back(rdmR[i]);
        for (size_t g = 0; g < nodes.size(); ++g) {
            Rgb m;
            for (int c = 0; c < 3; ++c) {
                Eigen::ArrayXf exponent = Eigen::ArrayXf::Zero(count);
                for (int j = 0; j < functions; ++j)
                    exponent +=
                        phi(static_cast<Eigen::Index>(g), j) * a.row(3 * j + c).array().transpose();
                m[c] = static_cast<double>((exponent.exp() * w.array()).sum());
            }
            e.modelM[g].push_back(m);
            e.rdmM[g].push_back(rdmM[g][i]);
        }
    }
    return e;
}

}  // namespace

PoissonFit fitPoissonLogLinear(const std::vector<FamilyCalibrationPoint>& points,
                               const Eigen::MatrixXd& basis,
                               const std::vector<CalibrationFeatures>& features,
                               const std::vector<bool>& active) {
    const int terms = static_cast<int>(basis.cols());
    const int unknowns = terms * kFeatures;
    std::vector<int> fitted;  // the coefficients fitted; the others stay 0
    for (int u = 0; u < unknowns; ++u)
        if (active.empty() || active[static_cast<size_t>(u)]) fitted.push_back(u);
    Eigen::VectorXd beta = Eigen::VectorXd::Zero(unknowns);
    // log s of a point for the coefficients b.
    auto logScale = [&](const Eigen::VectorXd& b, const FamilyCalibrationPoint& p) {
        const CalibrationFeatures& f = features[static_cast<size_t>(p.group)];
        double eta = 0;
        for (int k = 0; k < terms; ++k) {
            double coefficient = 0;
            for (int l = 0; l < kFeatures; ++l) coefficient += b[k * kFeatures + l] * f[l];
            eta += coefficient * basis(p.bin, k);
        }
        return eta;
    };
    // The objective sum n (mu - y log mu) up to a constant, mu = E exp(eta).
    auto objective = [&](const Eigen::VectorXd& b) {
        double sum = 0;
        for (const FamilyCalibrationPoint& p : points) {
            const double eta = logScale(b, p);
            sum += p.paths * (p.model * std::exp(eta) - p.rdm * eta);
        }
        return sum;
    };
    double current = objective(beta);
    PoissonFit fit;
    for (int iteration = 0; iteration < kNewtonIterations; ++iteration) {
        Eigen::MatrixXd h = Eigen::MatrixXd::Zero(unknowns, unknowns);
        Eigen::VectorXd g = Eigen::VectorXd::Zero(unknowns);
        // Points come group by group: accumulate each group's basis
        // moments, then their Kronecker product with f f^T.
        Eigen::MatrixXd hb = Eigen::MatrixXd::Zero(terms, terms);
        Eigen::VectorXd gb = Eigen::VectorXd::Zero(terms);
        auto flush = [&](const FamilyCalibrationPoint& last) {
            const CalibrationFeatures& f = features[static_cast<size_t>(last.group)];
            const Eigen::Map<const Eigen::Matrix<double, kFeatures, 1>> fv(f.data());
            const Eigen::Matrix<double, kFeatures, kFeatures> ff = fv * fv.transpose();
            for (int i = 0; i < terms; ++i) {
                g.segment<kFeatures>(i * kFeatures) += gb[i] * fv;
                for (int j = 0; j < terms; ++j)
                    h.block<kFeatures, kFeatures>(i * kFeatures, j * kFeatures) += hb(i, j) * ff;
            }
            hb.setZero();
            gb.setZero();
        };
        for (size_t q = 0; q < points.size(); ++q) {
            const FamilyCalibrationPoint& p = points[q];
            const double mu = p.model * std::exp(logScale(beta, p));
            const auto b = basis.row(p.bin).transpose();
            hb.noalias() += (p.paths * mu) * b * b.transpose();
            gb.noalias() += (p.paths * (mu - p.rdm)) * b;
            if (q + 1 == points.size() || points[q + 1].group != p.group) flush(p);
        }
        // A small ridge keeps features that no yarn varies (a zero-width
        // box) from making h singular.
        const double ridge = 1e-9 * std::max(h.diagonal().mean(), 1e-300);
        h.diagonal().array() += ridge;
        g += ridge * beta;
        Eigen::VectorXd step = Eigen::VectorXd::Zero(unknowns);
        const Eigen::MatrixXd hFree = h(fitted, fitted);
        const Eigen::VectorXd gFree = g(fitted);
        const Eigen::VectorXd stepFree = hFree.ldlt().solve(gFree);
        step(fitted) = stepFree;
        double t = 1;
        bool improved = false;
        for (int halving = 0; halving < 30; ++halving, t *= 0.5) {
            const Eigen::VectorXd next = beta - t * step;
            const double value = objective(next);
            if (value <= current) {
                improved = current - value > 1e-12 * std::fabs(current);
                beta = next, current = value;
                break;
            }
        }
        fit.iterations = iteration + 1;
        if (!improved) break;
    }
    fit.beta.assign(beta.data(), beta.data() + unknowns);
    // The energies' error, each point weighted by its paths: sum n |E s - y| / sum n y.
    double before = 0, after = 0, total = 0;
    for (const FamilyCalibrationPoint& p : points) {
        const double scaled =
            p.model * std::exp(std::clamp(logScale(beta, p), -EnergyCalibration::kMaxLogScale,
                                          EnergyCalibration::kMaxLogScale));
        before += p.paths * std::fabs(p.model - p.rdm);
        after += p.paths * std::fabs(scaled - p.rdm);
        total += p.paths * p.rdm;
    }
    if (total > 0) fit.errorBefore = before / total, fit.errorAfter = after / total;
    return fit;
}

FamilyCalibration fitFamilyCalibration(const FamilyModel& model,
                                       const std::vector<FamilyCalibrationYarn>& yarns,
                                       const RdmBins& bins, int degree, bool multipleScattering,
                                       int threads, bool quiet, nlohmann::json* summary) {
    FamilyCalibration cal;
    if (degree < 0 || yarns.empty()) return cal;
    FamilyModel plain = model;
    plain.calibration = {};
    // Without M's calibration there is no M system; its one node (any
    // colour) holds zeros, a scale of 1.
    const std::vector<double> nodes =
        multipleScattering ? colourCalibrationNodes(plain.colour.range()) : std::vector<double>{};
    tbb::task_arena arena(threads > 0 ? threads : tbb::this_task_arena::max_concurrency());

    // The energies, yarn by yarn.
    std::vector<YarnEnergies> energies(yarns.size());
    {
        Progress progress("calibration energies", yarns.size(), quiet);
        arena.execute([&] {
            tbb::parallel_for(size_t(0), yarns.size(), [&](size_t y) {
                energies[y] = yarnEnergies(plain, yarns[y], bins, nodes);
                progress.add(1);
            });
        });
        progress.finish();
    }

    // The systems: R, then M at every node.
    const int terms = EnergyCalibration::termCount(degree);
    Eigen::MatrixXd basis(static_cast<Eigen::Index>(bins.incidentCount()), terms);
    for (size_t i = 0; i < bins.incidentCount(); ++i) {
        std::vector<double> row(static_cast<size_t>(terms));
        EnergyCalibration::basis(bins.incidentCentre(i), degree, row.data());
        for (int k = 0; k < terms; ++k) basis(static_cast<Eigen::Index>(i), k) = row[k];
    }
    // Group 3 y + c: yarn y's channel c.
    std::vector<CalibrationFeatures> features;
    for (size_t y = 0; y < yarns.size(); ++y)
        for (int c = 0; c < 3; ++c)
            features.push_back(familyCalibrationFeatures(plain.box, yarns[y].point, c));
    const size_t systems = 1 + nodes.size();
    std::vector<std::vector<FamilyCalibrationPoint>> points(systems);
    for (size_t y = 0; y < yarns.size(); ++y) {
        const YarnEnergies& e = energies[y];
        for (int c = 0; c < 3; ++c)
            for (size_t s = 0; s < systems; ++s)
                for (size_t k = 0; k < e.bin.size(); ++k) {
                    const double modelE = s == 0 ? e.modelR[k][c] : e.modelM[s - 1][k][c];
                    const double rdmE = s == 0 ? e.rdmR[k][c] : e.rdmM[s - 1][k][c];
                    if (!(modelE > 0)) continue;  // nothing to scale
                    points[s].push_back(
                        {e.bin[k], static_cast<int32_t>(3 * y + c), e.paths[k], modelE, rdmE});
                }
    }
    // Every basis term has a coefficient shared by all yarns (feature 1);
    // only the terms up to a feature degree follow the other features.
    auto activeUpTo = [&](int featureDegree) {
        std::vector<bool> active(static_cast<size_t>(terms * kFeatures), false);
        for (int a = 0; a <= std::min(1, degree); ++a)
            for (int b = 0; b <= degree - a; ++b)
                for (int c = 0; c <= degree - a - b; ++c) {
                    const int k = EnergyCalibration::termIndex(a, b, c, degree);
                    for (int l = 0; l < kFeatures; ++l)
                        active[static_cast<size_t>(k * kFeatures + l)] =
                            l == 0 || a + b + c <= featureDegree;
                }
        return active;
    };
    const std::vector<bool> activeR = activeUpTo(kFamilyCalibrationFeatureDegreeR);
    const std::vector<bool> activeM = activeUpTo(kFamilyCalibrationFeatureDegreeM);
    std::vector<PoissonFit> fits(systems);
    arena.execute([&] {
        tbb::parallel_for(size_t(0), systems, [&](size_t s) {
            fits[s] = fitPoissonLogLinear(points[s], basis, features, s == 0 ? activeR : activeM);
        });
    });

    cal.degree = degree;
    cal.cTT = nodes;
    cal.r = fits[0].beta;
    for (size_t g = 0; g < nodes.size(); ++g) cal.m.push_back(fits[1 + g].beta);
    if (!multipleScattering) {
        cal.cTT = {plain.colour.range().hi};
        cal.m = {std::vector<double>(cal.r.size(), 0.0)};
    }
    if (summary) {
        nlohmann::json perNode = nlohmann::json::array();
        for (size_t g = 0; g < nodes.size(); ++g)
            perNode.push_back({{"c_tt", nodes[g]},
                               {"iterations", fits[1 + g].iterations},
                               {"energy_rel_error_before", fits[1 + g].errorBefore},
                               {"energy_rel_error_after", fits[1 + g].errorAfter}});
        *summary = {{"degree", degree},
                    {"feature_degree",
                     {{"r", std::min(degree, kFamilyCalibrationFeatureDegreeR)},
                      {"m", std::min(degree, kFamilyCalibrationFeatureDegreeM)}}},
                    {"yarns", yarns.size()},
                    {"min_paths", kFamilyCalibrationMinPaths},
                    {"r",
                     {{"points", points[0].size()},
                      {"iterations", fits[0].iterations},
                      {"energy_rel_error_before", fits[0].errorBefore},
                      {"energy_rel_error_after", fits[0].errorAfter}}},
                    {"m", multipleScattering ? perNode : nlohmann::json()}};
    }
    return cal;
}

}  // namespace weft
