// Training the T and M networks (train.h): Adam on mini-batches drawn from the RDM.
#include "weft/fit/train.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "weft/core/error.h"
#include "weft/core/progress.h"
#include "weft/core/rng.h"
#include "weft/fit/metrics.h"
#include "weft/fit/mlp.h"
#include "weft/fit/mlp_batch.h"
#include "weft/fit/model_maps.h"
#include "weft/yarn/colour_basis.h"

namespace weft {

namespace {

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

// The rows of a training chunk: the network's inputs and targets, plus
// `extraInputs` rows after the inputs that only the loss reads (a colour).
struct ChunkRows {
    int inputs, targets, extraInputs = 0;
};

// Trains `net` with Adam. fill(rng, x, target) writes one chunk of samples
// (x.capacity() of them) drawn with rng; lossAndGradient(batch, x, target,
// gradient) returns the chunk's mean loss and its gradient, with `batch` the
// chunk's training passes (mlp_batch.h). The chunks of a step run in parallel
// in `arena`, or one after the other when it is null. Returns the loss curve.
template <typename Fill, typename LossAndGradient>
LossCurve train(Mlp<float>& net, const NetworkTraining& cfg, uint64_t seed, uint64_t netId,
                tbb::task_arena* arena, Progress& progress, bool parallelRestarts,
                const ChunkRows& rows, const Fill& fill, const LossAndGradient& lossAndGradient) {
    std::vector<int> chunkSize(kChunks, cfg.batch / kChunks);
    for (int c = 0; c < cfg.batch % kChunks; ++c) ++chunkSize[c];
    std::vector<BatchRows> x, target;
    std::vector<MlpBatch> batches;
    std::vector<std::vector<float>> gradient(kChunks);
    std::vector<float> chunkLoss(kChunks), total(net.parameters().size());
    for (int c = 0; c < kChunks; ++c) {
        const int capacity = std::max(1, chunkSize[c]);
        x.emplace_back(rows.inputs + rows.extraInputs, capacity);
        target.emplace_back(rows.targets, capacity);
        batches.emplace_back(net, capacity);
    }
    Adam<float> adam(net.parameters().size(), cfg.learningRate);
    const int64_t logEvery = std::max<int64_t>(1, cfg.steps / 200);
    LossCurve curve;
    double intervalLoss = 0;
    int64_t intervalSteps = 0;
    for (int64_t step = 0; step < cfg.steps; ++step) {
        auto chunk = [&](int c) {
            if (chunkSize[c] == 0) return;
            Rng rng((netId << 48) ^ (static_cast<uint64_t>(step) * kChunks + c), seed);
            fill(rng, x[c], target[c]);
            chunkLoss[c] = lossAndGradient(batches[c], x[c], target[c], gradient[c]);
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

// train() for a network whose outputs are the targets, under cfg.loss.
template <typename Fill>
LossCurve trainPlain(Mlp<float>& net, const NetworkTraining& cfg, uint64_t seed, uint64_t netId,
                     tbb::task_arena* arena, Progress& progress, bool parallelRestarts,
                     const Fill& fill) {
    return train(net, cfg, seed, netId, arena, progress, parallelRestarts,
                 {net.inputs(), net.outputs()}, fill,
                 [&](MlpBatch& batch, const BatchRows& x, const BatchRows& target,
                     std::vector<float>& gradient) {
                     return batch.lossAndGradient(x, target, x.capacity(), cfg.loss, gradient);
                 });
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

// Outgoing theta rows in proportion to their solid angle (the metric's weight).
std::vector<double> outgoingRowCdf(const RdmBins& bins) {
    std::vector<double> rowCdf(bins.thetaO);
    double sum = 0;
    for (int t = 0; t < bins.thetaO; ++t)
        rowCdf[t] = sum += bins.outgoingSolidAngle(static_cast<size_t>(t) * bins.phiO);
    return rowCdf;
}

// One training sample of an M network: incident bin uniform, outgoing row in
// proportion to its solid angle, azimuth bin uniform, directions jittered
// inside the bins (or their centres).
struct MSample {
    size_t i, o;
    Vec3 wi, wo;
};

MSample drawMSample(Rng& rng, const RdmBins& bins, const std::vector<double>& rowCdf, bool jitter) {
    MSample m;
    m.i = std::min<size_t>(bins.incidentCount() - 1, rng.uniform() * bins.incidentCount());
    const size_t row = drawFromCdf(rowCdf, rng.uniform());
    m.o = row * bins.phiO + std::min<size_t>(bins.phiO - 1, rng.uniform() * bins.phiO);
    const double u1 = rng.uniform(), u2 = rng.uniform();
    const double u3 = rng.uniform(), u4 = rng.uniform();
    m.wi = jitter ? bins.incidentDirectionIn(m.i, u1, u2) : bins.incidentCentre(m.i);
    m.wo = jitter ? bins.outgoingDirectionIn(m.o, u3, u4) : bins.outgoingCentre(m.o);
    return m;
}

// The loss of a colour-conditioned M network on M_c = exp(sum_j a_jc
// phi_j(C_TT,c)) (yarn/colour_basis.h), the sample's C_TT in rows
// colourRow.. of x; its gradient into `gradient`.
// With weightRow >= 0, rows weightRow.. hold a weight per channel that
// multiplies the sample's squared residual.
float conditionedLossAndGradient(MlpBatch& passes, const BatchRows& x, const BatchRows& target,
                                 int colourRow, const ColourBasis& basis, Loss loss,
                                 std::vector<float>& gradient, int weightRow = -1) {
    const int batch = x.capacity(), functions = basis.functions();
    passes.forward(x, batch);
    double total = 0;
    double phi[ColourBasis::kMaxFunctions];
    for (int k = 0; k < batch; ++k)
        for (int c = 0; c < 3; ++c) {
            basis.eval(x(colourRow + c, k), phi);
            double z = 0;
            for (int j = 0; j < functions; ++j) z += passes.output(3 * j + c)[k] * phi[j];
            const float y = static_cast<float>(std::exp(std::min(z, 80.0)));
            const auto [diff, dDiff] = lossResidual(loss, y, target(c, k));
            const double weight = weightRow >= 0 ? x(weightRow + c, k) : 1.0;
            total += weight * diff * diff;
            const double dz = 2.0 * weight * diff * dDiff * y / static_cast<double>(batch);
            for (int j = 0; j < functions; ++j)
                passes.outputGradient(3 * j + c)[k] = static_cast<float>(dz * phi[j]);
        }
    passes.backward(gradient);
    return static_cast<float>(total / static_cast<double>(batch));
}

// The 3-7-7-1 network is small for the sharp grazing-angle edge of P(T | wi)
// and its result depends on the initialisation: train `restarts` T networks
// of `inputs` inputs from different seeds (in parallel, each on one thread)
// with fill (trainPlain) and keep the one of least error(weights); its loss
// curve into *curve, its error into *bestError.
template <typename Fill, typename Error>
NetworkWeights bestTransmissionNetwork(int inputs, const FitConfig& config, uint64_t seed,
                                       uint64_t netId, tbb::task_arena& arena, const char* label,
                                       bool quiet, const Fill& fill, const Error& error,
                                       LossCurve* curve, double* bestError) {
    const int restarts = config.t.restarts;
    std::vector<Mlp<float>> nets(restarts);
    std::vector<LossCurve> curves(restarts);
    std::vector<double> errors(restarts);
    Progress progress(label, static_cast<uint64_t>(config.t.steps) * restarts, quiet);
    arena.execute([&] {
        tbb::parallel_for(0, restarts, [&](int r) {
            const uint64_t netSeed = mixBits(seed + 0x9e3779b97f4a7c15ULL * static_cast<uint64_t>(r));
            nets[r] =
                Mlp<float>(widthsOf(inputs, config.t.hidden, 1), OutputFunction::Sigmoid, netSeed);
            curves[r] = trainPlain(nets[r], config.t, netSeed, netId, nullptr, progress,
                                   restarts > 1, fill);
            errors[r] = error(nets[r].weights());
        });
    });
    const int best =
        static_cast<int>(std::min_element(errors.begin(), errors.end()) - errors.begin());
    progress.setStatus("best rmse " + std::to_string(errors[best]));
    progress.finish();
    *curve = curves[best];
    if (bestError) *bestError = errors[best];
    return nets[best].weights();
}

}  // namespace

NetworkWeights fitTransmissionNetwork(const RdmData& rdm, const FitConfig& config, uint64_t seed,
                                      tbb::task_arena& arena, bool quiet, LossCurve* curve) {
    const RdmBins& bins = rdm.bins;
    std::vector<double> cdf(bins.incidentCount());
    double sum = 0;
    for (size_t i = 0; i < cdf.size(); ++i) cdf[i] = sum += static_cast<double>(rdm.count[i]);
    if (sum <= 0) throw InputError(rdm.dir + ": the gather has no paths (count.npy is all zero)");
    const auto fill = [&](Rng& rng, BatchRows& x, BatchRows& target) {
        for (int k = 0; k < x.capacity(); ++k) {
            const size_t i = drawFromCdf(cdf, rng.uniform());
            const double u1 = rng.uniform(), u2 = rng.uniform();
            setInputColumn(
                x, k, config.jitter ? bins.incidentDirectionIn(i, u1, u2) : bins.incidentCentre(i));
            target(0, k) = static_cast<float>(rdm.pT[i]);
        }
    };
    const auto error = [&](const NetworkWeights& net) {
        return transmissionError(transmissionMap(net, bins), rdm).weighted;
    };
    return bestTransmissionNetwork(3, config, seed, 1, arena, "fit T", quiet, fill, error, curve,
                                   nullptr);
}

NetworkWeights fitMultipleScatteringNetwork(const RdmData& rdm, const FitConfig& config,
                                           uint64_t seed, tbb::task_arena& arena, bool quiet,
                                           LossCurve* curve) {
    const RdmBins& bins = rdm.bins;
    const size_t nOut = bins.outgoingCount();
    const std::vector<double> rowCdf = outgoingRowCdf(bins);
    Mlp<float> net(widthsOf(6, config.m.hidden, 3), OutputFunction::Exp, seed);
    Progress progress("fit M", static_cast<uint64_t>(config.m.steps), quiet);
    *curve = trainPlain(net, config.m, seed, 2, &arena, progress, false,
                        [&](Rng& rng, BatchRows& x, BatchRows& target) {
                            for (int k = 0; k < x.capacity(); ++k) {
                                const MSample m = drawMSample(rng, bins, rowCdf, config.jitter);
                                setInputColumn(x, k, m.wi, m.wo);
                                const float* t = &rdm.rdmM[(m.i * nOut + m.o) * 3];
                                target(0, k) = t[0], target(1, k) = t[1], target(2, k) = t[2];
                            }
                        });
    progress.finish();
    return net.weights();
}

NetworkWeights fitColourConditionedMNetwork(const ColourTargets& targets,
                                            const ColourBasis& basis, const FitConfig& config,
                                            uint64_t seed, tbb::task_arena& arena, bool quiet,
                                            LossCurve* curve) {
    const RdmBins& bins = targets.bins();
    const std::vector<double> rowCdf = outgoingRowCdf(bins);
    const ColourRange range = basis.range();
    Mlp<float> net(widthsOf(6, config.m.hidden, 3 * basis.functions()), OutputFunction::Identity,
                   seed);
    Progress progress("fit M (any colour)", static_cast<uint64_t>(config.m.steps), quiet);
    // Inputs: (wi, wo); extra rows: the sample's C_TT per channel, uniform in the range.
    const auto fill = [&](Rng& rng, BatchRows& x, BatchRows& target) {
        for (int k = 0; k < x.capacity(); ++k) {
            const MSample m = drawMSample(rng, bins, rowCdf, config.jitter);
            setInputColumn(x, k, m.wi, m.wo);
            Rgb colour;
            for (int c = 0; c < 3; ++c)
                colour[c] = range.lo + (range.hi - range.lo) * rng.uniform();
            const Rgb t = targets.value(m.i, m.o, colour);
            for (int c = 0; c < 3; ++c) {
                x(6 + c, k) = static_cast<float>(colour[c]);
                target(c, k) = static_cast<float>(t[c]);
            }
        }
    };
    const auto lossAndGradient = [&](MlpBatch& passes, const BatchRows& x, const BatchRows& target,
                                     std::vector<float>& gradient) {
        return conditionedLossAndGradient(passes, x, target, 6, basis, config.m.loss, gradient);
    };
    *curve =
        train(net, config.m, seed, 3, &arena, progress, false, {6, 3, 3}, fill, lossAndGradient);
    progress.finish();
    return net.weights();
}

namespace {

// Path-count-weighted RMS error of a family T network over every yarn's incident bins.
double familyTransmissionError(const NetworkWeights& net,
                               const std::vector<FamilyTrainingPoint>& points,
                               const RdmBins& bins) {
    double sum = 0, weight = 0;
    for (const FamilyTrainingPoint& p : points) {
        const NetworkWeights folded =
            foldConstantInputs(net, 3, {p.inputs[0], p.inputs[1], p.inputs[2]});
        const std::vector<double> pT = transmissionMap(folded, bins);
        for (size_t i = 0; i < pT.size(); ++i) {
            const double count = p.incidentCdf[i] - (i ? p.incidentCdf[i - 1] : 0.0);
            sum += count * (pT[i] - p.pT[i]) * (pT[i] - p.pT[i]);
            weight += count;
        }
    }
    return weight > 0 ? std::sqrt(sum / weight) : 0.0;
}

size_t drawPoint(Rng& rng, size_t count) {
    return std::min<size_t>(count - 1,
                            static_cast<size_t>(rng.uniform() * static_cast<double>(count)));
}

}  // namespace

NetworkWeights fitFamilyTransmissionNetwork(const std::vector<FamilyTrainingPoint>& points,
                                            const RdmBins& bins, const FitConfig& config,
                                            uint64_t seed, tbb::task_arena& arena, bool quiet,
                                            LossCurve* curve, double* rmse) {
    if (points.empty()) throw InputError("a family fit needs at least one yarn");
    const auto fill = [&](Rng& rng, BatchRows& x, BatchRows& target) {
        for (int k = 0; k < x.capacity(); ++k) {
            const FamilyTrainingPoint& p = points[drawPoint(rng, points.size())];
            const size_t i = drawFromCdf(p.incidentCdf, rng.uniform());
            const double u1 = rng.uniform(), u2 = rng.uniform();
            setInputColumn(
                x, k, config.jitter ? bins.incidentDirectionIn(i, u1, u2) : bins.incidentCentre(i));
            for (int d = 0; d < 3; ++d) x(3 + d, k) = p.inputs[d];
            target(0, k) = static_cast<float>(p.pT[i]);
        }
    };
    const auto error = [&](const NetworkWeights& net) {
        return familyTransmissionError(net, points, bins);
    };
    return bestTransmissionNetwork(6, config, seed, 4, arena, "fit T (family)", quiet, fill, error,
                                   curve, rmse);
}

NetworkWeights fitFamilyMNetwork(const std::vector<FamilyTrainingPoint>& points,
                                 const ColourBasis& basis, const FitConfig& config, uint64_t seed,
                                 tbb::task_arena& arena, bool quiet, LossCurve* curve) {
    if (points.empty()) throw InputError("a family fit needs at least one yarn");
    const RdmBins& bins = points.front().m->bins();
    const std::vector<double> rowCdf = outgoingRowCdf(bins);
    const ColourRange range = basis.range();
    constexpr int kInputs = 6 + FamilyBox::kDimensions;
    Mlp<float> net(widthsOf(kInputs, config.m.hidden, 3 * basis.functions()),
                   OutputFunction::Identity, seed);
    Progress progress("fit M (family)", static_cast<uint64_t>(config.m.steps), quiet);
    // Inputs: (wi, wo) and the yarn's parameters; extra rows: C_TT per
    // channel, then the weight per channel (1 / the yarn's mean M squared).
    const auto fill = [&](Rng& rng, BatchRows& x, BatchRows& target) {
        for (int k = 0; k < x.capacity(); ++k) {
            const FamilyTrainingPoint& p = points[drawPoint(rng, points.size())];
            const MSample m = drawMSample(rng, bins, rowCdf, config.jitter);
            setInputColumn(x, k, m.wi, m.wo);
            for (int d = 0; d < FamilyBox::kDimensions; ++d) x(6 + d, k) = p.inputs[d];
            Rgb colour;
            for (int c = 0; c < 3; ++c) {
                const double u = rng.uniform();
                colour[c] = range.lo + (range.hi - range.lo) * u;
                // The mean at u, linear between the nodes.
                const double node = u * (kFamilyMeanNodes - 1);
                const int g = std::min(static_cast<int>(node), kFamilyMeanNodes - 2);
                const double f = node - g;
                const double mean = (1 - f) * p.meanM[c][g] + f * p.meanM[c][g + 1];
                x(kInputs + 3 + c, k) = static_cast<float>(1.0 / std::max(mean * mean, 1e-12));
            }
            const Rgb t = p.m->value(m.i, m.o, colour);
            for (int c = 0; c < 3; ++c) {
                x(kInputs + c, k) = static_cast<float>(colour[c]);
                target(c, k) = static_cast<float>(t[c]);
            }
        }
    };
    const auto lossAndGradient = [&](MlpBatch& passes, const BatchRows& x, const BatchRows& target,
                                     std::vector<float>& gradient) {
        return conditionedLossAndGradient(passes, x, target, kInputs, basis, config.m.loss,
                                          gradient, kInputs + 3);
    };
    *curve = train(net, config.m, seed, 5, &arena, progress, false, {kInputs, 3, 6}, fill,
                   lossAndGradient);
    progress.finish();
    return net.weights();
}

}  // namespace weft
