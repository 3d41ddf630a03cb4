// The M sampling lobe's parameters (sampling_fit.h): Nelder-Mead on the
// second moment of the M estimator over the RDM grid.
#include "weft/fit/sampling_fit.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>

#include "weft/fit/metrics.h"
#include "weft/yarn/yarn_lobes.h"

namespace weft {

namespace {

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

}  // namespace

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

}  // namespace weft
