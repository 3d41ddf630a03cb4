// weft/core/quadrature.h — Gauss-Legendre rules: the one home of their tables.
//
// The 4-point rule, on composite panels, for the integrals of the yarn BSDF
// over outgoing directions (yarn_integrals.h and the energy guard of
// yarn_bsdf.h); the 8-point rule for the normaliser of the longitudinal
// Gaussian (fiber/longitudinal.cpp). An n-point rule integrates polynomials
// of degree up to 2n - 1 on [-1, 1] exactly (quadrature_test.cpp). The
// literals are fixed: results that use them stay the same bit for bit.
#pragma once

#include <cstddef>
#include <vector>

namespace weft::quadrature {

// The 4-point rule on [-1, 1]: nodes in increasing order and their weights.
inline constexpr double kGaussLegendre4Nodes[4] = {-0.8611363115940526, -0.3399810435848563,
                                                   0.3399810435848563, 0.8611363115940526};
inline constexpr double kGaussLegendre4Weights[4] = {0.3478548451374538, 0.6521451548625461,
                                                     0.6521451548625461, 0.3478548451374538};

// The 8-point rule on [-1, 1], by its positive half: the nodes are +-x[k]
// with weight w[k] each (k = 0..3, x increasing).
inline constexpr double kGaussLegendre8HalfNodes[4] = {0.1834346424956498, 0.5255324099163290,
                                                       0.7966664774136267, 0.9602898564975363};
inline constexpr double kGaussLegendre8HalfWeights[4] = {0.3626837833783620, 0.3137066458778873,
                                                         0.2223810344533745, 0.1012285362903763};

// Edges of `count` equal panels on [a, b], appended.
inline void uniformEdges(double a, double b, int count, std::vector<double>* edges) {
    for (int k = 0; k <= count; ++k) edges->push_back(a + (b - a) * k / count);
}

// Appends the nodes and weights of the 4-point Gauss-Legendre rule on every
// panel between consecutive (sorted) edges; empty panels are skipped.
inline void panelRule(const std::vector<double>& edges, std::vector<double>* x,
                      std::vector<double>* w) {
    for (size_t k = 0; k + 1 < edges.size(); ++k) {
        const double a = edges[k], b = edges[k + 1];
        if (!(b - a > 1e-12)) continue;
        for (int n = 0; n < 4; ++n) {
            x->push_back(0.5 * (a + b) + 0.5 * (b - a) * kGaussLegendre4Nodes[n]);
            w->push_back(0.5 * (b - a) * kGaussLegendre4Weights[n]);
        }
    }
}

}  // namespace weft::quadrature
