#include "weft/fit/mlp_batch.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "weft/core/rng.h"

namespace weft {
namespace {

using MlpD = Mlp<double>;

struct Case {
    std::vector<int> widths;
    std::vector<bool> prelu;
    OutputFunction output;
    Loss loss;
    int samples;  // not a multiple of kMlpSampleGroup where it can be
};

std::vector<Case> cases() {
    return {
        {{3, 7, 7, 1}, {true, true, false}, OutputFunction::Sigmoid, Loss::Mse, 37},
        {{6, 21, 21, 21, 3}, {true, true, true, false}, OutputFunction::Exp, Loss::LogMse, 128},
        {{6, 21, 21, 21, 3}, {true, true, true, false}, OutputFunction::Exp, Loss::Mse, 5},
        // A hidden layer without PReLU, and an identity output.
        {{9, 12, 10, 6}, {true, false, false}, OutputFunction::Identity, Loss::Mse, 50},
    };
}

// A network of the case's shape with random weights and slopes away from the
// default (both sides of every PReLU matter), the float copy, and a chunk.
struct Network {
    MlpD reference;
    Mlp<float> net;
    BatchRows x, target;
    MlpD::Matrix xd, td;
};

Network randomNetwork(const Case& c, uint64_t seed) {
    Rng rng(seed, 3);
    MlpD reference(c.widths, c.prelu, c.output, seed);
    for (double& p : reference.parameters()) p += 0.2 * (rng.uniform() - 0.5);
    for (size_t l = 0; l + 1 < c.widths.size(); ++l)
        for (int k = 0; k < reference.preluSlopes(static_cast<int>(l)).size(); ++k)
            reference.preluSlopes(static_cast<int>(l))(k) = 0.05 + 0.5 * rng.uniform();
    // The float network holds the double one's weights rounded to float, and
    // the reference then takes those rounded values back.
    Mlp<float> net(reference.weights());
    reference = MlpD(net.weights());
    const int in = c.widths.front(), out = c.widths.back();
    BatchRows x(in + 1, c.samples), target(out, c.samples);
    MlpD::Matrix xd(in, c.samples), td(out, c.samples);
    for (int k = 0; k < c.samples; ++k) {
        for (int r = 0; r < in; ++r) xd(r, k) = x(r, k) = static_cast<float>(2 * rng.uniform() - 1);
        x(in, k) = 1e30f;  // a row after the inputs, which the passes must not read
        for (int r = 0; r < out; ++r) td(r, k) = target(r, k) = static_cast<float>(rng.uniform());
    }
    return {std::move(reference), std::move(net), std::move(x), std::move(target), xd, td};
}

// The largest |a - b| over max(|b|, floor).
double worstRelative(const std::vector<float>& a, const std::vector<double>& b, double floor) {
    double worst = 0;
    for (size_t k = 0; k < b.size(); ++k)
        worst = std::max(worst, std::fabs(a[k] - b[k]) / std::max(std::fabs(b[k]), floor));
    return worst;
}

// Outputs, loss and gradient of every kernel against Mlp<double> (whose
// gradient mlp_test holds to finite differences), for whole and partial
// groups of samples.
TEST(MlpBatch, EveryKernelMatchesTheDoubleReference) {
    for (const MlpBatchKernel& kernel : mlpBatchKernels()) {
        for (const Case& c : cases()) {
            Network s = randomNetwork(c, 11);
            MlpBatch batch(s.net, 128, kernel);
            std::vector<float> gradient;
            const float loss = batch.lossAndGradient(s.x, s.target, c.samples, c.loss, gradient);
            const MlpD::Matrix y = s.reference.forward(s.xd);
            for (int k = 0; k < c.samples; ++k)
                for (int r = 0; r < c.widths.back(); ++r)
                    ASSERT_NEAR(batch.output(r)[k], y(r, k),
                                2e-5 * std::max(1.0, std::fabs(y(r, k))))
                        << kernel.target << " output " << r << " sample " << k;
            std::vector<double> expected;
            const double expectedLoss =
                s.reference.lossAndGradient(s.xd, s.td, c.loss, {}, expected);
            EXPECT_NEAR(loss, expectedLoss, 1e-4 * expectedLoss) << kernel.target;
            ASSERT_EQ(gradient.size(), expected.size());
            double largest = 0;
            for (double g : expected) largest = std::max(largest, std::fabs(g));
            EXPECT_LT(worstRelative(gradient, expected, 1e-3 * largest), 1e-3)
                << kernel.target << " " << c.widths.size() << " layers, " << c.samples
                << " samples";
        }
    }
}

// backward() for a loss the caller computes (dL/dy given), as the colour
// fit does, against Mlp<double>::backward with the same dL/dy.
TEST(MlpBatch, BackwardOfAGivenOutputGradientMatchesTheReference) {
    const Case c = cases()[1];
    Network s = randomNetwork(c, 5);
    MlpBatch batch(s.net, 100);
    batch.forward(s.x, 100);
    Rng rng(8, 8);
    MlpD::Matrix dy(3, 128);
    dy.setZero();
    for (int k = 0; k < 100; ++k)
        for (int r = 0; r < 3; ++r)
            dy(r, k) = batch.outputGradient(r)[k] = static_cast<float>(rng.uniform() - 0.5);
    // Stale values past the samples must not count.
    for (int r = 0; r < 3; ++r) batch.outputGradient(r)[110] = 1e20f;
    std::vector<float> gradient;
    batch.backward(gradient);
    MlpD::Matrix xd(6, 128);
    xd.setZero();
    xd.leftCols(100) = s.xd.leftCols(100);
    std::vector<double> expected;
    s.reference.backward(s.reference.forwardTape(xd.leftCols(100)), dy.leftCols(100), expected);
    double largest = 0;
    for (double g : expected) largest = std::max(largest, std::fabs(g));
    EXPECT_LT(worstRelative(gradient, expected, 1e-3 * largest), 1e-3);
}

// The kernels with FMA (AVX2, AVX-512) give the same bits: a fit does not
// depend on which of them the CPU runs.
TEST(MlpBatch, KernelsWithFusedMultiplyAddAgreeBitForBit) {
    std::vector<std::vector<float>> results;
    std::vector<const char*> names;
    for (const MlpBatchKernel& kernel : mlpBatchKernels()) {
        if (!kernel.fusedMultiplyAdd) continue;
        std::vector<float> all;
        for (const Case& c : cases()) {
            Network s = randomNetwork(c, 3);
            MlpBatch batch(s.net, 128, kernel);
            std::vector<float> gradient;
            all.push_back(batch.lossAndGradient(s.x, s.target, c.samples, c.loss, gradient));
            all.insert(all.end(), gradient.begin(), gradient.end());
            for (int r = 0; r < c.widths.back(); ++r)
                all.insert(all.end(), batch.output(r), batch.output(r) + c.samples);
        }
        results.push_back(all);
        names.push_back(kernel.target);
    }
    if (results.size() < 2) GTEST_SKIP() << "this CPU runs at most one kernel with FMA";
    for (size_t k = 1; k < results.size(); ++k)
        EXPECT_EQ(
            0, std::memcmp(results[0].data(), results[k].data(), results[0].size() * sizeof(float)))
            << names[0] << " vs " << names[k];
}

TEST(MlpBatch, RefusesAChunkThatDoesNotFit) {
    Mlp<float> net({3, 4, 1}, OutputFunction::Sigmoid, 1);
    MlpBatch batch(net, 16);
    BatchRows x(3, 32), narrow(2, 16), shortTarget(1, 4);
    EXPECT_THROW(batch.forward(x, 17), std::invalid_argument);
    EXPECT_THROW(batch.forward(narrow, 4), std::invalid_argument);
    std::vector<float> gradient;
    EXPECT_THROW(batch.lossAndGradient(BatchRows(3, 16), shortTarget, 8, Loss::Mse, gradient),
                 std::invalid_argument);
}

}  // namespace
}  // namespace weft
