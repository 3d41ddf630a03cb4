// Tests for weft/core/quadrature.h: each Gauss-Legendre rule integrates the
// monomials x^d on [-1, 1] exactly for d <= 2n - 1 (and not for d = 2n, so
// that the test would see a wrong node), and the panel rule is exact
// panel by panel.
#include "weft/core/quadrature.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace weft::quadrature {
namespace {

// The integral of x^d over [-1, 1].
double monomialIntegral(int d) { return d % 2 ? 0.0 : 2.0 / (d + 1); }

// The rule's sum for x^d.
double ruleSum(const std::vector<double>& nodes, const std::vector<double>& weights, int d) {
    double sum = 0;
    for (size_t k = 0; k < nodes.size(); ++k) sum += weights[k] * std::pow(nodes[k], d);
    return sum;
}

std::vector<double> fourPointNodes() {
    return {std::begin(kGaussLegendre4Nodes), std::end(kGaussLegendre4Nodes)};
}
std::vector<double> fourPointWeights() {
    return {std::begin(kGaussLegendre4Weights), std::end(kGaussLegendre4Weights)};
}
// The 8-point rule from its positive half: -x[k] and +x[k], each with w[k].
std::vector<double> eightPointNodes() {
    std::vector<double> nodes;
    for (double x : kGaussLegendre8HalfNodes) nodes.insert(nodes.end(), {-x, x});
    return nodes;
}
std::vector<double> eightPointWeights() {
    std::vector<double> weights;
    for (double w : kGaussLegendre8HalfWeights) weights.insert(weights.end(), {w, w});
    return weights;
}

void expectExactUpToDegree(const std::vector<double>& nodes, const std::vector<double>& weights,
                           int n) {
    ASSERT_EQ(nodes.size(), static_cast<size_t>(n));
    for (int d = 0; d <= 2 * n - 1; ++d)
        EXPECT_NEAR(ruleSum(nodes, weights, d), monomialIntegral(d), 1e-14)
            << n << "-point rule, degree " << d;
    // Degree 2n is the first the rule gets wrong.
    EXPECT_GT(std::fabs(ruleSum(nodes, weights, 2 * n) - monomialIntegral(2 * n)), 1e-6)
        << n << "-point rule, degree " << 2 * n;
}

TEST(Quadrature, FourPointRuleIsExactUpToDegreeSeven) {
    expectExactUpToDegree(fourPointNodes(), fourPointWeights(), 4);
    for (int k = 1; k < 4; ++k) EXPECT_LT(kGaussLegendre4Nodes[k - 1], kGaussLegendre4Nodes[k]);
}

TEST(Quadrature, EightPointRuleIsExactUpToDegreeFifteen) {
    expectExactUpToDegree(eightPointNodes(), eightPointWeights(), 8);
    for (int k = 1; k < 4; ++k)
        EXPECT_LT(kGaussLegendre8HalfNodes[k - 1], kGaussLegendre8HalfNodes[k]);
}

TEST(Quadrature, PanelRuleIsExactOnEveryPanel) {
    // x^7 - 2 x^3 + 1 on [-0.5, 2] over uneven panels (one empty, skipped).
    const std::vector<double> edges = {-0.5, 0.25, 0.25, 1.0, 2.0};
    std::vector<double> x, w;
    panelRule(edges, &x, &w);
    ASSERT_EQ(x.size(), 12u);
    ASSERT_EQ(w.size(), 12u);
    double sum = 0;
    for (size_t k = 0; k < x.size(); ++k)
        sum += w[k] * (std::pow(x[k], 7) - 2 * std::pow(x[k], 3) + 1);
    const auto antiderivative = [](double t) {
        return std::pow(t, 8) / 8 - std::pow(t, 4) / 2 + t;
    };
    EXPECT_NEAR(sum, antiderivative(2.0) - antiderivative(-0.5), 1e-12);
    std::vector<double> uniform;
    uniformEdges(-1.0, 3.0, 4, &uniform);
    EXPECT_EQ(uniform, (std::vector<double>{-1.0, 0.0, 1.0, 2.0, 3.0}));
}

}  // namespace
}  // namespace weft::quadrature
