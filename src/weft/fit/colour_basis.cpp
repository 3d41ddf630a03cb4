#include "weft/fit/colour_basis.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "weft/core/error.h"
#include "weft/core/limits.h"
#include "weft/fit/metrics.h"

namespace weft {

namespace {

// Cells with fewer recorded M paths are left out of the fit: one or two
// paths make a bare monomial C_TT^k, noise rather than the ply's shape.
constexpr int kMinPathsPerCell = 4;

// The coarse error grid of fit/metrics.h, no finer than the gather's own bins.
RdmBins coarseGridFor(const RdmBins& fine) {
    const RdmBins& c = kCoarseErrorBins;
    return {std::min(fine.thetaI, c.thetaI), std::min(fine.phiI, c.phiI),
            std::min(fine.thetaO, c.thetaO), std::min(fine.phiO, c.phiO)};
}

}  // namespace

ColourBasisFit fitColourBasis(const std::vector<ColourPath>& paths, const RdmBins& bins,
                              const std::vector<int64_t>& count, const ColourRange& range,
                              int functions, int nodes) {
    range.validate("colour range");
    checkRange("colour basis functions =", functions, 2, ColourBasis::kMaxFunctions);
    checkRange("colour basis nodes =", nodes, functions, 1024);
    const RdmBins coarse = coarseGridFor(bins);
    const std::vector<size_t> inMap = incidentMap(bins, coarse), outMap = outgoingMap(bins, coarse);
    const size_t cOut = coarse.outgoingCount(), nOut = bins.outgoingCount();
    // Fine incident bins per coarse one and coarse solid angles: the metric's
    // weight of a coarse cell is W_O P^2 with P = (sum of values) / (n_I W_O).
    std::vector<double> finePerCoarseIn(coarse.incidentCount(), 0.0), coarseSolid(cOut, 0.0);
    for (size_t i = 0; i < inMap.size(); ++i) finePerCoarseIn[inMap[i]] += 1;
    for (size_t o = 0; o < nOut; ++o) coarseSolid[outMap[o]] += bins.outgoingSolidAngle(o);

    // M paths sorted by coarse cell, so that each cell is summed once.
    std::vector<size_t> cellOf(paths.size());
    std::vector<uint32_t> order;
    int maxK = 0;
    for (size_t p = 0; p < paths.size(); ++p) {
        const ColourPath& path = paths[p];
        if (path.kind != ColourPath::M) continue;
        cellOf[p] = inMap[path.incidentBin] * cOut + outMap[path.outgoingBin];
        order.push_back(static_cast<uint32_t>(p));
        maxK = std::max(maxK, path.ttEvents);
    }
    std::stable_sort(order.begin(), order.end(),
                     [&](uint32_t a, uint32_t b) { return cellOf[a] < cellOf[b]; });
    // exp(-k s_g) for every k and node.
    const double sLo = -std::log(range.hi), sHi = -std::log(range.lo);
    std::vector<double> power(static_cast<size_t>(maxK + 1) * nodes);
    for (int k = 0; k <= maxK; ++k)
        for (int g = 0; g < nodes; ++g)
            power[static_cast<size_t>(k) * nodes + g] =
                std::exp(-k * (sLo + (sHi - sLo) * g / (nodes - 1)));

    // Calls f(V, weight) for every (coarse cell, channel) row with enough
    // paths: V[g] = the cell's sum of W0 C_TT^k / count over its paths at node g,
    // weight = 1 / (n_I^2 W_O), so that weight V^2 is the metric's weight.
    const auto forEachRow = [&](auto&& f) {
        Eigen::ArrayXd values[3] = {Eigen::ArrayXd(nodes), Eigen::ArrayXd(nodes),
                                    Eigen::ArrayXd(nodes)};
        size_t begin = 0;
        while (begin < order.size()) {
            const size_t cell = cellOf[order[begin]];
            size_t end = begin;
            for (auto& v : values) v.setZero();
            while (end < order.size() && cellOf[order[end]] == cell) {
                const ColourPath& p = paths[order[end]];
                const double* pw = &power[static_cast<size_t>(p.ttEvents) * nodes];
                const double perPath = 1.0 / static_cast<double>(count[p.incidentBin]);
                for (int c = 0; c < 3; ++c) {
                    const double w = p.weight[c] * perPath;
                    for (int g = 0; g < nodes; ++g) values[c][g] += w * pw[g];
                }
                ++end;
            }
            if (end - begin >= static_cast<size_t>(kMinPathsPerCell)) {
                const double nI = finePerCoarseIn[cell / cOut], solid = coarseSolid[cell % cOut];
                for (int c = 0; c < 3; ++c)
                    if ((values[c] > 0).all()) f(values[c], 1.0 / (nI * nI * solid));
            }
            begin = end;
        }
    };

    // Energy-weighted Gram matrix of the centred log rows: a log error d on a
    // value V costs about weight V^2 d^2 in the metric.
    Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(nodes, nodes);
    int64_t rows = 0;
    forEachRow([&](const Eigen::ArrayXd& v, double weight) {
        Eigen::VectorXd centred = v.log().matrix();
        centred.array() -= centred.mean();
        gram.noalias() += (weight * v.square().mean()) * centred * centred.transpose();
        ++rows;
    });
    if (rows < functions)
        throw InputError("the any-colour gather has " + std::to_string(rows) +
                         " coarse cells with at least " + std::to_string(kMinPathsPerCell) +
                         " M paths, too few for " + std::to_string(functions) +
                         " colour functions: gather more paths");
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(gram);
    std::vector<std::vector<double>> table(functions, std::vector<double>(nodes, 1.0));
    for (int j = 1; j < functions; ++j) {
        // Largest eigenvalues last; unit vectors scaled to an RMS of 1, sign
        // fixed so that the function decreases from the first node to the last.
        Eigen::VectorXd v = eigen.eigenvectors().col(nodes - j) * std::sqrt(nodes);
        if (v(nodes - 1) > v(0)) v = -v;
        for (int g = 0; g < nodes; ++g) table[j][g] = v(g);
    }
    ColourBasisFit fit;
    fit.basis = ColourBasis(range, table);
    fit.rows = rows;

    // The truncation error per node: each row's least-squares fit in the basis.
    Eigen::MatrixXd basis(nodes, functions);
    for (int j = 0; j < functions; ++j)
        for (int g = 0; g < nodes; ++g) basis(g, j) = table[j][g];
    const auto qr = basis.colPivHouseholderQr();
    Eigen::ArrayXd errorSum = Eigen::ArrayXd::Zero(nodes), refSum = Eigen::ArrayXd::Zero(nodes);
    forEachRow([&](const Eigen::ArrayXd& v, double weight) {
        const Eigen::VectorXd logV = v.log().matrix();
        const Eigen::ArrayXd approx = (basis * qr.solve(logV)).array().exp();
        errorSum += weight * (approx - v).square();
        refSum += weight * v.square();
    });
    fit.nodeError.resize(nodes);
    for (int g = 0; g < nodes; ++g) fit.nodeError[g] = std::sqrt(errorSum[g] / refSum[g]);
    fit.meanError = std::accumulate(fit.nodeError.begin(), fit.nodeError.end(), 0.0) / nodes;
    fit.worstError = *std::max_element(fit.nodeError.begin(), fit.nodeError.end());
    return fit;
}

}  // namespace weft
