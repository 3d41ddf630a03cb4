// weft/core/quadrature.h — composite Gauss-Legendre rules on panels, for the
// integrals of the yarn BSDF over outgoing directions (yarn_integrals.h and
// the energy guard of yarn_bsdf.h).
#pragma once

#include <vector>

namespace weft::quadrature {

// Edges of `count` equal panels on [a, b], appended.
inline void uniformEdges(double a, double b, int count, std::vector<double>* edges) {
    for (int k = 0; k <= count; ++k) edges->push_back(a + (b - a) * k / count);
}

// Appends the nodes and weights of the 4-point Gauss-Legendre rule on every
// panel between consecutive (sorted) edges; empty panels are skipped.
inline void panelRule(const std::vector<double>& edges, std::vector<double>* x,
                      std::vector<double>* w) {
    constexpr double kNodes[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                                  0.8611363115940526};
    constexpr double kWeights[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                                    0.3478548451374538};
    for (size_t k = 0; k + 1 < edges.size(); ++k) {
        const double a = edges[k], b = edges[k + 1];
        if (!(b - a > 1e-12)) continue;
        for (int n = 0; n < 4; ++n) {
            x->push_back(0.5 * (a + b) + 0.5 * (b - a) * kNodes[n]);
            w->push_back(0.5 * (b - a) * kWeights[n]);
        }
    }
}

}  // namespace weft::quadrature
