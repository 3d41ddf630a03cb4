#include "weft/fit/fit.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

#include "weft/core/error.h"
#include "weft/core/json_file.h"
#include "weft/core/json_reader.h"
#include "weft/core/math.h"
#include "weft/core/progress.h"
#include "weft/core/rng.h"
#include "weft/fit/metrics.h"
#include "weft/fit/sphere_rule.h"
#include "weft/fit/yarn_lobes.h"

namespace weft {

// ---------------------------------------------------------------- config --

namespace {

const char* lossName(Loss loss) { return loss == Loss::Mse ? "mse" : "log-mse"; }

nlohmann::json trainingToJson(const NetworkTraining& t) {
    return {{"hidden", t.hidden},          {"steps", t.steps}, {"restarts", t.restarts},
            {"batch", t.batch},            {"learning_rate", t.learningRate},
            {"final_learning_rate", t.finalLearningRate}, {"loss", lossName(t.loss)}};
}

NetworkTraining trainingFromJson(JsonObjectReader r, NetworkTraining t) {
    r.allowKeys(
        {"hidden", "steps", "restarts", "batch", "learning_rate", "final_learning_rate", "loss"});
    if (r.has("hidden")) {
        t.hidden.clear();
        for (int64_t w : r.integers("hidden", 1, 8, {1, 256}, "(layer widths)"))
            t.hidden.push_back(static_cast<int>(w));
    }
    if (r.has("steps")) t.steps = r.integer("steps", {1, 100'000'000});
    if (r.has("restarts")) t.restarts = static_cast<int>(r.integer("restarts", {1, 64}));
    if (r.has("batch")) t.batch = static_cast<int>(r.integer("batch", {8, 1 << 20}));
    const NumberRange rate = NumberRange::openClosed(0, 1);
    if (r.has("learning_rate")) t.learningRate = r.number("learning_rate", rate);
    if (r.has("final_learning_rate")) t.finalLearningRate = r.number("final_learning_rate", rate);
    if (r.has("loss")) t.loss = r.oneOf("loss", {"mse", "log-mse"}) == 0 ? Loss::Mse : Loss::LogMse;
    return t;
}

}  // namespace

FitConfig FitConfig::fromJson(const nlohmann::json& j, const std::string& source) {
    JsonObjectReader r(j, source);
    r.allowKeys({"t_net", "m_net", "jitter", "masking", "threads", "energy_calibration_degree"});
    FitConfig c;
    if (r.has("t_net")) c.t = trainingFromJson(r.object("t_net"), c.t);
    if (r.has("m_net")) c.m = trainingFromJson(r.object("m_net"), c.m);
    if (r.has("jitter")) c.jitter = r.boolean("jitter");
    if (r.has("masking")) c.masking = r.boolean("masking");
    if (r.has("energy_calibration_degree"))
        c.calibrationDegree = static_cast<int>(r.integer(
            "energy_calibration_degree", {-1, EnergyCalibration::kMaxDegree, "(-1: off)"}));
    if (r.has("threads"))
        c.threads = static_cast<int>(r.integer("threads", {0, 1024, "(0: all cores)"}));
    return c;
}

FitConfig FitConfig::fromJsonFile(const std::string& path) {
    return fromJson(readJsonFile(path), path);
}

nlohmann::json FitConfig::toJson() const {
    return {{"t_net", trainingToJson(t)},
            {"m_net", trainingToJson(m)},
            {"jitter", jitter},
            {"masking", masking},
            {"energy_calibration_degree", calibrationDegree},
            {"threads", threads}};
}

// -------------------------------------------------------------- training --

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Every batch is split into this many chunks, whatever the thread count, and
// their gradients are summed in chunk order: the fit depends on the seed only.
constexpr int kChunks = 8;

double learningRateAt(const NetworkTraining& t, int64_t step) {
    if (t.steps <= 1) return t.learningRate;
    const double f = static_cast<double>(step) / static_cast<double>(t.steps - 1);
    return t.learningRate * std::pow(t.finalLearningRate / t.learningRate, f);
}

std::string formatLoss(double loss) {
    char buf[48];
    std::snprintf(buf, sizeof buf, "loss %.3e", loss);
    return buf;
}

// Trains `net` with Adam. fill(rng, x, target) writes one chunk of samples
// (columns) drawn with rng. The chunks of a step run in parallel in `arena`,
// or one after the other when it is null. Returns the loss curve.
template <typename Fill>
LossCurve train(Mlp<float>& net, const NetworkTraining& cfg, uint64_t seed, uint64_t netId,
                tbb::task_arena* arena, Progress& progress, bool parallelRestarts,
                const Fill& fill) {
    using Matrix = Mlp<float>::Matrix;
    std::vector<int> chunkSize(kChunks, cfg.batch / kChunks);
    for (int c = 0; c < cfg.batch % kChunks; ++c) ++chunkSize[c];
    std::vector<Matrix> x(kChunks), target(kChunks);
    std::vector<std::vector<float>> gradient(kChunks);
    std::vector<float> chunkLoss(kChunks), total(net.parameters().size());
    for (int c = 0; c < kChunks; ++c) {
        x[c].resize(net.inputs(), chunkSize[c]);
        target[c].resize(net.outputs(), chunkSize[c]);
    }
    Adam<float> adam(net.parameters().size(), cfg.learningRate);
    const Mlp<float>::Vector noWeights;
    const int64_t logEvery = std::max<int64_t>(1, cfg.steps / 200);
    LossCurve curve;
    double intervalLoss = 0;
    int64_t intervalSteps = 0;
    for (int64_t step = 0; step < cfg.steps; ++step) {
        auto chunk = [&](int c) {
            if (chunkSize[c] == 0) return;
            Rng rng((netId << 48) ^ (static_cast<uint64_t>(step) * kChunks + c), seed);
            fill(rng, x[c], target[c]);
            chunkLoss[c] = net.lossAndGradient(x[c], target[c], cfg.loss, noWeights, gradient[c]);
        };
        if (arena) arena->execute([&] { tbb::parallel_for(0, kChunks, chunk); });
        else for (int c = 0; c < kChunks; ++c) chunk(c);
        std::fill(total.begin(), total.end(), 0.0f);
        double loss = 0;
        for (int c = 0; c < kChunks; ++c) {
            if (chunkSize[c] == 0) continue;
            const float share = static_cast<float>(chunkSize[c]) / static_cast<float>(cfg.batch);
            for (size_t k = 0; k < total.size(); ++k) total[k] += share * gradient[c][k];
            loss += share * chunkLoss[c];
        }
        adam.setLearningRate(learningRateAt(cfg, step));
        adam.step(net.parameters(), total);
        intervalLoss += loss;
        ++intervalSteps;
        if (intervalSteps == logEvery || step + 1 == cfg.steps) {
            curve.step.push_back(static_cast<double>(step + 1));
            curve.loss.push_back(intervalLoss / static_cast<double>(intervalSteps));
            if (!parallelRestarts) progress.setStatus(formatLoss(curve.loss.back()));
            intervalLoss = 0;
            intervalSteps = 0;
        }
        progress.add(1);
    }
    return curve;
}

// Index drawn from a cumulative table (last entry = total) with u in [0, 1).
size_t drawFromCdf(const std::vector<double>& cdf, double u) {
    const double target = u * cdf.back();
    const size_t k = std::upper_bound(cdf.begin(), cdf.end(), target) - cdf.begin();
    return std::min(k, cdf.size() - 1);
}

std::vector<int> widthsOf(int inputs, const std::vector<int>& hidden, int outputs) {
    std::vector<int> w = {inputs};
    w.insert(w.end(), hidden.begin(), hidden.end());
    w.push_back(outputs);
    return w;
}

void putColumn(Mlp<float>::Matrix& m, Eigen::Index col, const Vec3& a) {
    m(0, col) = static_cast<float>(a.x), m(1, col) = static_cast<float>(a.y),
          m(2, col) = static_cast<float>(a.z);
}

// A column (wi, wo) of M network inputs.
void putColumn(Mlp<float>::Matrix& m, Eigen::Index col, const Vec3& wi, const Vec3& wo) {
    putColumn(m, col, wi);
    m(3, col) = static_cast<float>(wo.x), m(4, col) = static_cast<float>(wo.y),
          m(5, col) = static_cast<float>(wo.z);
}

// Path-count-weighted RMS error of a T network against the gathered P(T | wi).
double transmissionRmse(const Mlp<float>& net, const RdmData& rdm) {
    YarnModel probe;
    probe.tNet = net;
    const std::vector<double> pT = modelTransmissionMap(probe, rdm.bins);
    double se = 0, total = 0;
    for (size_t i = 0; i < pT.size(); ++i) {
        const double w = static_cast<double>(rdm.count[i]);
        se += w * (pT[i] - rdm.pT[i]) * (pT[i] - rdm.pT[i]);
        total += w;
    }
    return total > 0 ? std::sqrt(se / total) : 0.0;
}

// The 3-7-7-1 network is small for the sharp grazing-angle edge of P(T | wi)
// and its result depends on the initialisation: train `restarts` networks
// from different seeds (in parallel, each on one thread) and keep the best.
Mlp<float> fitTransmission(const RdmData& rdm, const FitConfig& config, uint64_t seed,
                           tbb::task_arena& arena, bool quiet, LossCurve* curve) {
    const RdmBins& bins = rdm.bins;
    std::vector<double> cdf(bins.incidentCount());
    double sum = 0;
    for (size_t i = 0; i < cdf.size(); ++i) cdf[i] = sum += static_cast<double>(rdm.count[i]);
    if (sum <= 0) throw InputError(rdm.dir + ": the gather has no paths (count.npy is all zero)");
    const int restarts = config.t.restarts;
    std::vector<Mlp<float>> nets(restarts);
    std::vector<LossCurve> curves(restarts);
    std::vector<double> rmse(restarts);
    Progress progress("fit T", static_cast<uint64_t>(config.t.steps) * restarts, quiet);
    arena.execute([&] {
        tbb::parallel_for(0, restarts, [&](int r) {
            const uint64_t netSeed = mixBits(seed + 0x9e3779b97f4a7c15ULL * static_cast<uint64_t>(r));
            nets[r] = Mlp<float>(widthsOf(3, config.t.hidden, 1), OutputFunction::Sigmoid, netSeed);
            curves[r] = train(nets[r], config.t, netSeed, 1, nullptr, progress, restarts > 1,
                              [&](Rng& rng, Mlp<float>::Matrix& x, Mlp<float>::Matrix& target) {
                                  for (Eigen::Index k = 0; k < x.cols(); ++k) {
                                      const size_t i = drawFromCdf(cdf, rng.uniform());
                                      const double u1 = rng.uniform(), u2 = rng.uniform();
                                      putColumn(x, k,
                                                config.jitter ? bins.incidentDirectionIn(i, u1, u2)
                                                              : bins.incidentCentre(i));
                                      target(0, k) = static_cast<float>(rdm.pT[i]);
                                  }
                              });
            rmse[r] = transmissionRmse(nets[r], rdm);
        });
    });
    const int best = static_cast<int>(std::min_element(rmse.begin(), rmse.end()) - rmse.begin());
    progress.setStatus("best rmse " + std::to_string(rmse[best]));
    progress.finish();
    *curve = curves[best];
    return nets[best];
}

Mlp<float> fitMultipleScattering(const RdmData& rdm, const FitConfig& config, uint64_t seed,
                                 tbb::task_arena& arena, bool quiet, LossCurve* curve) {
    const RdmBins& bins = rdm.bins;
    const size_t nIn = bins.incidentCount(), nOut = bins.outgoingCount();
    // Outgoing theta rows in proportion to their solid angle (the metric's weight).
    std::vector<double> rowCdf(bins.thetaO);
    double sum = 0;
    for (int t = 0; t < bins.thetaO; ++t)
        rowCdf[t] = sum += bins.outgoingSolidAngle(static_cast<size_t>(t) * bins.phiO);
    Mlp<float> net(widthsOf(6, config.m.hidden, 3), OutputFunction::Exp, seed);
    Progress progress("fit M", static_cast<uint64_t>(config.m.steps), quiet);
    *curve = train(net, config.m, seed, 2, &arena, progress, false,
                   [&](Rng& rng, Mlp<float>::Matrix& x, Mlp<float>::Matrix& target) {
                       for (Eigen::Index k = 0; k < x.cols(); ++k) {
                           const size_t i = std::min<size_t>(nIn - 1, rng.uniform() * nIn);
                           const size_t row = drawFromCdf(rowCdf, rng.uniform());
                           const size_t o =
                               row * bins.phiO +
                               std::min<size_t>(bins.phiO - 1, rng.uniform() * bins.phiO);
                           const double u1 = rng.uniform(), u2 = rng.uniform();
                           const double u3 = rng.uniform(), u4 = rng.uniform();
                           const Vec3 wi = config.jitter ? bins.incidentDirectionIn(i, u1, u2)
                                                         : bins.incidentCentre(i);
                           const Vec3 wo = config.jitter ? bins.outgoingDirectionIn(o, u3, u4)
                                                         : bins.outgoingCentre(o);
                           putColumn(x, k, wi, wo);
                           const float* t = &rdm.rdmM[(i * nOut + o) * 3];
                           target(0, k) = t[0], target(1, k) = t[1], target(2, k) = t[2];
                       }
                   });
    progress.finish();
    return net;
}

// Energy of a (TI, PI, TO, PO, 3) map: mean over channels of
// sum_i w_i sum_o v ΔΩ_o with w_i the incident solid angle (normalised).
double mapEnergy(const std::vector<float>& map, const RdmBins& bins) {
    const size_t nIn = bins.incidentCount(), nOut = bins.outgoingCount();
    double energy = 0, incidentTotal = 0;
    for (size_t i = 0; i < nIn; ++i) {
        const double wi = bins.incidentSolidAngle(i);
        incidentTotal += wi;
        double e = 0;
        for (size_t o = 0; o < nOut; ++o) {
            const float* v = &map[(i * nOut + o) * 3];
            e += (v[0] + v[1] + v[2]) / 3.0 * bins.outgoingSolidAngle(o);
        }
        energy += wi * e;
    }
    return energy / incidentTotal;
}

// Least-squares masking coefficients: minimise
// sum W_O (m(mu_I, mu_O) P_eq8 - P_rdm)^2 over the coarse grid and channels.
std::vector<double> maskingLeastSquares(const std::vector<float>& eq8, const std::vector<float>& rdmR,
                               const RdmBins& fine) {
    const RdmBins& coarse = kCoarseErrorBins;
    const std::vector<double> pe = poolRdm(eq8, fine, coarse), pr = poolRdm(rdmR, fine, coarse);
    const size_t cIn = coarse.incidentCount(), cOut = coarse.outgoingCount();
    Eigen::Matrix4d a = Eigen::Matrix4d::Zero();
    Eigen::Vector4d b = Eigen::Vector4d::Zero();
    for (size_t I = 0; I < cIn; ++I) {
        const double muI = coarse.incidentCentre(I).z;
        for (size_t O = 0; O < cOut; ++O) {
            const double muO = coarse.outgoingCentre(O).z;
            if (muO <= 0) continue;
            const double w = coarse.outgoingSolidAngle(O);
            const auto basis = maskingBasis(muI, muO);
            for (int c = 0; c < 3; ++c) {
                const size_t k = (I * cOut + O) * 3 + c;
                Eigen::Vector4d v;
                for (int j = 0; j < kMaskingCoefficients; ++j) v[j] = basis[j] * pe[k];
                a += w * v * v.transpose();
                b += w * v * pr[k];
            }
        }
    }
    const Eigen::Vector4d c = a.ldlt().solve(b);
    return {c[0], c[1], c[2], c[3]};
}

// ------------------------------------------------------- sampling lobe fit --

// The second moment of the M estimator, sum_O f^2 / pdf ΔΩ / (sum_O f ΔΩ)^2,
// averaged over incident directions (1 when pdf is proportional to f).
class SecondMomentObjective {
public:
    SecondMomentObjective(const YarnModel& model, const std::vector<float>& mMap,
                          const RdmBins& fine, tbb::task_arena& arena)
        : model_(model), arena_(arena) {
        // Coarse incident directions, fine outgoing ones: narrow lobes stay resolved.
        bins_ = {std::min(fine.thetaI, 11), std::min(fine.phiI, 45), fine.thetaO, fine.phiO};
        pooled_ = poolRdm(mMap, fine, bins_);
        const size_t nIn = bins_.incidentCount(), nOut = bins_.outgoingCount();
        solidAngle_.resize(nOut);
        for (size_t o = 0; o < nOut; ++o) solidAngle_[o] = bins_.outgoingSolidAngle(o);
        f_.resize(nIn * nOut);
        normaliser_.assign(nIn, 0.0);
        for (size_t i = 0; i < nIn; ++i)
            for (size_t o = 0; o < nOut; ++o) {
                const double* v = &pooled_[(i * nOut + o) * 3];
                f_[i * nOut + o] = (v[0] + v[1] + v[2]) / 3.0;
                normaliser_[i] += f_[i * nOut + o] * solidAngle_[o];
            }
        // The angles depend on the tilt only, not on the fitted parameters.
        const SamplingLobes lobes(model.fiber, model.rLobe.tiltDeg, SamplingParams{});
        for (size_t o = 0; o < nOut; ++o) outgoing_.push_back(lobes.anglesOf(bins_.outgoingCentre(o)));
        for (size_t i = 0; i < nIn; ++i) thetaI_.push_back(lobes.anglesOf(bins_.incidentCentre(i)).theta);
    }

    double operator()(const SamplingParams& p) const {
        const SamplingLobes lobes(model_.fiber, model_.rLobe.tiltDeg, p);
        const size_t nIn = bins_.incidentCount(), nOut = bins_.outgoingCount();
        std::vector<double> vonMises(nOut);
        for (size_t o = 0; o < nOut; ++o) vonMises[o] = lobes.vonMisesM(outgoing_[o].cosPhi);
        std::vector<double> perIncident(nIn, 0.0);
        arena_.execute([&] {
            tbb::parallel_for(size_t(0), nIn, [&](size_t i) {
                if (normaliser_[i] <= 0) return;
                const double inverseMass = lobes.longitudinalM().inverseMass(-thetaI_[i]);
                double m = 0;
                for (size_t o = 0; o < nOut; ++o) {
                    const double f = f_[i * nOut + o];
                    if (f <= 0) continue;
                    m += f * f / lobes.pdfM(thetaI_[i], inverseMass, outgoing_[o], vonMises[o]) *
                         solidAngle_[o];
                }
                perIncident[i] = m / (normaliser_[i] * normaliser_[i]);
            });
        });
        double total = 0;
        int used = 0;
        for (size_t i = 0; i < nIn; ++i)
            if (normaliser_[i] > 0) total += perIncident[i], ++used;
        return used > 0 ? total / used : 0.0;
    }

private:
    const YarnModel& model_;
    tbb::task_arena& arena_;
    RdmBins bins_;
    std::vector<double> pooled_, solidAngle_, f_, normaliser_;
    std::vector<SamplingLobes::Angles> outgoing_;
    std::vector<double> thetaI_;
};

double logistic(double x) { return 1.0 / (1.0 + std::exp(-x)); }

// (log beta, log gamma, logit kappa) -> parameters, clamped to their ranges.
SamplingParams samplingFromVector(const Eigen::Vector3d& v, double kappaR) {
    SamplingParams p;
    p.kappaR = kappaR;
    p.betaMDeg = std::clamp(std::exp(v[0]), 0.5, 90.0);
    p.gammaMDeg = std::clamp(std::exp(v[1]), 1.0, 180.0);
    p.kappaM = std::clamp(logistic(v[2]), 0.0, 0.99);
    return p;
}

// Nelder-Mead (standard coefficients) over 3 unconstrained variables.
template <typename F>
Eigen::Vector3d nelderMead(const F& f, Eigen::Vector3d start, double step, int iterations) {
    std::array<Eigen::Vector3d, 4> x;
    std::array<double, 4> y;
    x[0] = start;
    for (int k = 0; k < 3; ++k) {
        x[k + 1] = start;
        x[k + 1][k] += step;
    }
    for (int k = 0; k < 4; ++k) y[k] = f(x[k]);
    for (int it = 0; it < iterations; ++it) {
        std::array<int, 4> order = {0, 1, 2, 3};
        std::sort(order.begin(), order.end(), [&](int a, int b) { return y[a] < y[b]; });
        const int best = order[0], worst = order[3], second = order[2];
        Eigen::Vector3d centroid = (x[order[0]] + x[order[1]] + x[order[2]]) / 3.0;
        const Eigen::Vector3d reflected = centroid + (centroid - x[worst]);
        const double yr = f(reflected);
        if (yr < y[best]) {
            const Eigen::Vector3d expanded = centroid + 2.0 * (centroid - x[worst]);
            const double ye = f(expanded);
            if (ye < yr) x[worst] = expanded, y[worst] = ye;
            else x[worst] = reflected, y[worst] = yr;
        } else if (yr < y[second]) {
            x[worst] = reflected, y[worst] = yr;
        } else {
            const Eigen::Vector3d contracted = centroid + 0.5 * (x[worst] - centroid);
            const double yc = f(contracted);
            if (yc < y[worst]) {
                x[worst] = contracted, y[worst] = yc;
            } else {
                for (int k : {order[1], order[2], order[3]}) {
                    x[k] = x[best] + 0.5 * (x[k] - x[best]);
                    y[k] = f(x[k]);
                }
            }
        }
    }
    return x[std::min_element(y.begin(), y.end()) - y.begin()];
}

template <typename Eval>
void forEachIncident(tbb::task_arena* arena, size_t count, const Eval& eval) {
    auto run = [&] { tbb::parallel_for(size_t(0), count, eval); };
    if (arena) arena->execute(run);
    else run();
}

}  // namespace

// ------------------------------------------------------------ model maps --

std::vector<double> modelTransmissionMap(const YarnModel& model, const RdmBins& bins) {
    const size_t nIn = bins.incidentCount();
    if (!model.hasTransmissionLobe()) return std::vector<double>(nIn, 0.0);
    Mlp<float>::Matrix x(3, static_cast<Eigen::Index>(nIn));
    for (size_t i = 0; i < nIn; ++i) putColumn(x, static_cast<Eigen::Index>(i), bins.incidentCentre(i));
    const Mlp<float>::Matrix y = model.tNet.forward(x);
    std::vector<double> pT(nIn);
    for (size_t i = 0; i < nIn; ++i) pT[i] = y(0, static_cast<Eigen::Index>(i));
    return pT;
}

std::vector<float> modelReflectionMap(const YarnModel& model, const RdmBins& bins) {
    if (!model.hasReflectionLobe())
        return std::vector<float>(bins.incidentCount() * bins.outgoingCount() * 3, 0.0f);
    const std::vector<double> pT = modelTransmissionMap(model, bins);
    const RLobe lobe(model.fiber, model.rLobe);
    const size_t nIn = bins.incidentCount(), nOut = bins.outgoingCount();
    std::vector<float> map(nIn * nOut * 3);
    forEachIncident(nullptr, nIn, [&](size_t i) {
        const Vec3 wi = bins.incidentCentre(i);
        const Rgb scale = model.calibration.scales(wi).r;
        for (size_t o = 0; o < nOut; ++o) {
            const Rgb v = lobe.eval(wi, bins.outgoingCentre(o), pT[i]) * scale;
            for (int c = 0; c < 3; ++c) map[(i * nOut + o) * 3 + c] = static_cast<float>(v[c]);
        }
    });
    return map;
}

std::vector<float> modelMultipleScatteringMap(const YarnModel& model, const RdmBins& bins) {
    const size_t nIn = bins.incidentCount(), nOut = bins.outgoingCount();
    std::vector<Vec3> outgoing(nOut);
    for (size_t o = 0; o < nOut; ++o) outgoing[o] = bins.outgoingCentre(o);
    std::vector<float> map(nIn * nOut * 3);
    forEachIncident(nullptr, nIn, [&](size_t i) {
        Mlp<float>::Matrix x(6, static_cast<Eigen::Index>(nOut));
        const Vec3 wi = bins.incidentCentre(i);
        for (size_t o = 0; o < nOut; ++o) putColumn(x, static_cast<Eigen::Index>(o), wi, outgoing[o]);
        const Mlp<float>::Matrix y = model.mNet.forward(x);
        const Rgb scale = model.calibration.scales(wi).m;
        for (size_t o = 0; o < nOut; ++o)
            for (int c = 0; c < 3; ++c)
                map[(i * nOut + o) * 3 + c] =
                    static_cast<float>(y(c, static_cast<Eigen::Index>(o)) * scale[c]);
    });
    return map;
}

// ------------------------------------------------------- energy calibration --

namespace {

// Model energies of R and M (integrals over wo, yarn BSDF quadrature) and the
// RDM's (sums over outgoing bins) for every incident bin with enough paths.
struct BinEnergies {
    std::vector<size_t> bin;
    std::vector<Rgb> modelR, modelM, rdmR, rdmM;
    std::vector<double> pT;  // P(T) of the model at every incident bin centre
};

BinEnergies binEnergies(const YarnModel& model, const RdmData& rdm, int64_t minPaths,
                        tbb::task_arena& arena) {
    const RdmBins& bins = rdm.bins;
    const size_t nOut = bins.outgoingCount();
    BinEnergies e;
    for (size_t i = 0; i < bins.incidentCount(); ++i)
        if (rdm.count[i] >= minPaths) e.bin.push_back(i);
    const size_t n = e.bin.size();
    e.modelR.resize(n), e.modelM.resize(n), e.rdmR.resize(n), e.rdmM.resize(n);
    e.pT = modelTransmissionMap(model, bins);
    const std::vector<double>& pT = e.pT;
    const RLobe lobe(model.fiber, model.rLobe);
    const double betaR = radians(model.fiber.betaRDeg);
    arena.execute([&] {
        tbb::parallel_for(size_t(0), n, [&](size_t k) {
            const size_t i = e.bin[k];
            const Vec3 wi = bins.incidentCentre(i);
            const SphereRule rule = surfaceFiberSphereRule(lobe.frame(), betaR, wi);
            const auto nodes = static_cast<Eigen::Index>(rule.directions.size());
            Mlp<float>::Matrix x(6, nodes);
            Rgb r;
            for (Eigen::Index q = 0; q < nodes; ++q) {
                const Vec3& wo = rule.directions[static_cast<size_t>(q)];
                if (model.hasReflectionLobe())
                    r += lobe.eval(wi, wo, pT[i]) * rule.weights[static_cast<size_t>(q)];
                putColumn(x, q, wi, wo);
            }
            const Mlp<float>::Matrix y = model.mNet.forward(x);
            Rgb m;
            for (Eigen::Index q = 0; q < nodes; ++q)
                for (int c = 0; c < 3; ++c) m[c] += y(c, q) * rule.weights[static_cast<size_t>(q)];
            Rgb rr, rm;
            for (size_t o = 0; o < nOut; ++o) {
                const double omega = bins.outgoingSolidAngle(o);
                const size_t at = (i * nOut + o) * 3;
                for (int c = 0; c < 3; ++c) {
                    rr[c] += rdm.rdmR[at + c] * omega;
                    rm[c] += rdm.rdmM[at + c] * omega;
                }
            }
            e.modelR[k] = r, e.modelM[k] = m, e.rdmR[k] = rr, e.rdmM[k] = rm;
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
        auto rgb = [](const Rgb& c) { return nlohmann::json::array({c.r, c.g, c.b}); };
        *summary = {{"degree", degree},
                    {"degrees_chosen", {{"r", chosen[0]}, {"m", chosen[1]}}},
                    {"bins", e.bin.size()},
                    {"min_paths", kCalibrationMinPaths},
                    {"albedo_rel_error_mean_abs_before", rgb(before / n)},
                    {"albedo_rel_error_mean_abs_after", rgb(after / n)},
                    {"albedo_within_3_percent_after", static_cast<double>(within) / (3 * n)},
                    {"r_scale_range", {rgb(rScaleMin), rgb(rScaleMax)}},
                    {"m_scale_range", {rgb(mScaleMin), rgb(mScaleMax)}}};
    }
    return cal;
}

// ------------------------------------------------------------------ fit --

std::vector<double> fitMaskingCoefficients(const std::vector<float>& eq8,
                                           const std::vector<float>& rdmR, const RdmBins& bins) {
    return maskingLeastSquares(eq8, rdmR, bins);
}

SamplingParams fitSamplingLobe(const YarnModel& model, const std::vector<float>& mMap,
                               const RdmBins& bins, double kappaR, double* secondMoment,
                               int threads) {
    tbb::task_arena arena(threads > 0 ? threads : tbb::this_task_arena::max_concurrency());
    const SecondMomentObjective objective(model, mMap, bins, arena);
    const Eigen::Vector3d best = nelderMead(
        [&](const Eigen::Vector3d& v) { return objective(samplingFromVector(v, kappaR)); },
        Eigen::Vector3d(std::log(20.0), std::log(40.0), 0.0), 0.5, 120);
    const SamplingParams params = samplingFromVector(best, kappaR);
    if (secondMoment) *secondMoment = objective(params);
    return params;
}

namespace {

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
                  {{"path", rdm.dir},
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
Mlp<float> zeroTransmissionNetwork() {
    Mlp<float> net({3, 1}, {false}, OutputFunction::Sigmoid, 0);
    net.weight(0).setZero();
    net.bias(0).setConstant(-100.0f);
    return net;
}

}  // namespace

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
                       YarnAblation ablation) {
    const auto t0 = Clock::now();
    // Every step below sees the ablated model's target; the full model's is the gather itself.
    RdmData ablated;
    if (ablation != YarnAblation::None) ablated = ablationTarget(gathered, ablation);
    const RdmData& rdm = ablation != YarnAblation::None ? ablated : gathered;
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
                     ? fitTransmission(rdm, config, seed, arena, quiet, &report.tLoss)
                     : zeroTransmissionNetwork();
    report.tSeconds = secondsSince(phase);
    phase = Clock::now();
    const std::vector<double> pT = modelTransmissionMap(model, bins);
    double se = 0, seUnweighted = 0, countTotal = 0;
    for (size_t i = 0; i < pT.size(); ++i) {
        const double d = pT[i] - rdm.pT[i];
        se += static_cast<double>(rdm.count[i]) * d * d;
        seUnweighted += d * d;
        countTotal += static_cast<double>(rdm.count[i]);
    }
    report.tRmse = std::sqrt(se / countTotal);
    report.tRmseUnweighted = std::sqrt(seUnweighted / static_cast<double>(pT.size()));

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

    // 3. M network.
    phase = Clock::now();
    model.mNet = fitMultipleScattering(rdm, config, seed, arena, quiet, &report.mLoss);
    report.mSeconds = secondsSince(phase);
    report.mSamplesPerSecond =
        static_cast<double>(config.m.steps) * config.m.batch / std::max(report.mSeconds, 1e-9);
    std::vector<float> mFit;
    arena.execute([&] { mFit = modelMultipleScatteringMap(model, bins); });
    report.mRelL2 = coarseRelativeL2(mFit, rdm.rdmM, bins);
    phase = Clock::now();

    // 4-5. Energy calibration and sampling lobe.
    finishFit(model, rdm, config, threads, quiet, rFit, mFit, report);
    if (!model.hasReflectionLobe())
        report.rRelL2 = report.rRelL2Uncalibrated = std::numeric_limits<double>::quiet_NaN();

    report.seconds = secondsSince(t0);
    model.fit = fitRecord(report, config, seed, rdm, ablation);
    return result;
}

FitResult recalibrateYarnModel(const YarnModel& fitted, const RdmData& gathered,
                               const FitConfig& config, bool quiet) {
    const auto t0 = Clock::now();
    RdmData ablated;
    if (fitted.ablation != YarnAblation::None) ablated = ablationTarget(gathered, fitted.ablation);
    const RdmData& rdm = fitted.ablation != YarnAblation::None ? ablated : gathered;
    const int threads = config.threads > 0 ? config.threads : tbb::this_task_arena::max_concurrency();
    FitResult result;
    result.model = fitted;
    YarnModel& model = result.model;
    FitReport& report = result.report;
    model.calibration = EnergyCalibration{};
    std::vector<float> rFit, mFit;
    tbb::task_arena arena(threads);
    arena.execute([&] {
        rFit = modelReflectionMap(model, rdm.bins);
        mFit = modelMultipleScatteringMap(model, rdm.bins);
    });
    report.rRelL2 = coarseRelativeL2(rFit, rdm.rdmR, rdm.bins);
    report.mRelL2 = coarseRelativeL2(mFit, rdm.rdmM, rdm.bins);
    report.tRmse = model.hasTransmissionLobe() ? transmissionRmse(model.tNet, rdm) : 0.0;
    report.rRelL2Eq8 = fitted.fit.value("r_rel_l2_eq8", 0.0);
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
    record["recalibrated"] = {{"rdm", rdm.dir},
                              {"energy_calibration_degree", config.calibrationDegree},
                              {"seconds", report.seconds}};
    model.fit = record;
    return result;
}

}  // namespace weft
