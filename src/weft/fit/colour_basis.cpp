#include "weft/fit/colour_basis.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "weft/core/error.h"
#include "weft/core/json_reader.h"
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

void ColourRange::validate(const std::string& what) const {
    if (!(lo > 0 && lo < hi && hi <= 1))
        throw InputError(what + ": " + std::to_string(lo) + "," + std::to_string(hi) +
                         " is not a colour range LO,HI with 0 < LO < HI <= 1");
}

double ColourRange::sOf(double cTT) const { return -std::log(std::clamp(cTT, lo, hi)); }

ColourBasis::ColourBasis(ColourRange range, std::vector<std::vector<double>> table,
                         const std::string& source)
    : range_(range), table_(std::move(table)) {
    range_.validate(source + ": range");
    const int k = functions();
    if (k < 1 || k > kMaxFunctions)
        throw InputError(source + ": " + std::to_string(k) + " functions (allowed: 1.." +
                         std::to_string(kMaxFunctions) + ")");
    const size_t g = table_[0].size();
    if (g < 2 || g > 1024)
        throw InputError(source + ": " + std::to_string(g) + " nodes (allowed: 2..1024)");
    for (int j = 0; j < k; ++j) {
        if (table_[j].size() != g)
            throw InputError(source + ": function " + std::to_string(j) + " has " +
                             std::to_string(table_[j].size()) + " values, function 0 has " +
                             std::to_string(g));
        for (double v : table_[j])
            if (!std::isfinite(v) || std::abs(v) > 1e6 || (j == 0 && v != 1.0))
                throw InputError(
                    source + ": function " + std::to_string(j) + " has the value " +
                    std::to_string(v) +
                    (j == 0 ? " (function 0 is the constant 1)" : " (must be finite, |v| <= 1e6)"));
    }
    sLo_ = -std::log(range_.hi);
    sStep_ = (-std::log(range_.lo) - sLo_) / static_cast<double>(g - 1);
}

double ColourBasis::nodeS(int g) const { return sLo_ + sStep_ * g; }

void ColourBasis::eval(double cTT, double* phi) const {
    const double t = (range_.sOf(cTT) - sLo_) / sStep_;
    const int last = nodes() - 1;
    const int g = std::clamp(static_cast<int>(t), 0, last - 1);
    const double f = std::clamp(t - g, 0.0, 1.0);
    for (int j = 0; j < functions(); ++j)
        phi[j] = table_[j][g] + f * (table_[j][g + 1] - table_[j][g]);
}

nlohmann::json ColourBasis::toJson() const {
    return {{"c_tt_range", {range_.lo, range_.hi}},
            {"variable", "s = -ln(C_TT), nodes uniform in s from -ln(hi) to -ln(lo)"},
            {"functions", table_}};
}

ColourBasis ColourBasis::fromJson(const nlohmann::json& j, const std::string& source) {
    const JsonObjectReader r(j, source);
    const std::vector<double> range =
        r.numbers("c_tt_range", 2, NumberRange::openClosed(0, 1), "(lo, hi)");
    const nlohmann::json& f = r.value("functions");
    if (!f.is_array() || f.empty() || f.size() > kMaxFunctions)
        throw InputError(source + ": \"functions\" must be an array of 1.." +
                         std::to_string(kMaxFunctions) + " arrays of numbers");
    std::vector<std::vector<double>> table;
    for (const auto& row : f) {
        if (!row.is_array()) throw InputError(source + ": \"functions\" holds a non-array");
        std::vector<double> values;
        for (const auto& v : row) {
            if (!v.is_number()) throw InputError(source + ": \"functions\" holds a non-number");
            values.push_back(v.get<double>());
        }
        table.push_back(std::move(values));
    }
    return ColourBasis({range[0], range[1]}, std::move(table), source);
}

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
