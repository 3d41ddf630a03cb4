#include "weft/fit/mlp.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "weft/core/rng.h"
#include "weft/core/test_util.h"

namespace weft {
namespace {

using MlpD = Mlp<double>;

MlpD::Matrix randomMatrix(int rows, int cols, Rng& rng, double lo, double hi) {
    MlpD::Matrix m(rows, cols);
    for (int c = 0; c < cols; ++c)
        for (int r = 0; r < rows; ++r) m(r, c) = lo + (hi - lo) * rng.uniform();
    return m;
}

// Every parameter's analytic gradient against a central finite difference of
// the loss, for every output function and loss, with PReLU layers whose
// slopes are moved away from the default so that both branches matter.
TEST(Mlp, GradientMatchesFiniteDifferences) {
    Rng rng(1, 2);
    for (OutputFunction f : {OutputFunction::Identity, OutputFunction::Sigmoid, OutputFunction::Exp}) {
        for (Loss loss : {Loss::Mse, Loss::LogMse}) {
            MlpD net({4, 6, 5, 3}, f, 7);
            for (int l = 0; l < 2; ++l)
                for (int k = 0; k < net.preluSlopes(l).size(); ++k)
                    net.preluSlopes(l)(k) = 0.1 + 0.5 * rng.uniform();
            const MlpD::Matrix x = randomMatrix(4, 9, rng, -1.5, 1.5);
            const MlpD::Matrix t = randomMatrix(3, 9, rng, 0.1, 0.9);
            MlpD::Vector w(9);
            for (int c = 0; c < 9; ++c) w(c) = 0.5 + rng.uniform();
            std::vector<double> grad, unused;
            net.lossAndGradient(x, t, loss, w, grad);
            double worst = 0;
            for (size_t k = 0; k < net.parameters().size(); ++k) {
                const double saved = net.parameters()[k], h = 1e-6;
                net.parameters()[k] = saved + h;
                const double up = net.lossAndGradient(x, t, loss, w, unused);
                net.parameters()[k] = saved - h;
                const double down = net.lossAndGradient(x, t, loss, w, unused);
                net.parameters()[k] = saved;
                const double numeric = (up - down) / (2 * h);
                const double err = std::fabs(numeric - grad[k]) / std::max(1e-6, std::fabs(numeric));
                worst = std::max(worst, err);
                EXPECT_NEAR(grad[k], numeric, 1e-6 * std::max(1.0, std::fabs(numeric)))
                    << toString(f) << " parameter " << k;
            }
            std::printf("%s output, %s loss: largest relative gradient error %.2g\n",
                        toString(f).c_str(), loss == Loss::Mse ? "mse" : "log-mse", worst);
        }
    }
}

TEST(Mlp, ForwardMatchesHandComputation) {
    // 2-2-1 with sigmoid output, parameters set by hand.
    MlpD net({2, 2, 1}, OutputFunction::Sigmoid, 0);
    net.weight(0) << 1.0, -2.0, 0.5, 0.25;
    net.bias(0) << 0.1, -0.3;
    net.preluSlopes(0) << 0.2, 0.3;
    net.weight(1) << 1.5, -0.5;
    net.bias(1) << 0.05;
    MlpD::Matrix x(2, 1);
    x << 0.4, 0.7;
    // Hidden: z = (0.4 - 1.4 + 0.1, 0.2 + 0.175 - 0.3) = (-0.9, 0.075) -> (-0.18, 0.075).
    const double out = 1.5 * -0.18 - 0.5 * 0.075 + 0.05;
    EXPECT_NEAR(net.forward(x)(0, 0), 1.0 / (1.0 + std::exp(-out)), 1e-15);
}

TEST(Adam, ReachesTheMinimumOfAQuadratic) {
    // f(p) = sum_k c_k (p_k - m_k)^2 with very different curvatures.
    const std::vector<double> c = {1.0, 10.0, 0.1, 100.0}, m = {3.0, -2.0, 0.5, 1.0};
    std::vector<double> p(4, 0.0), g(4);
    Adam<double> adam(4, 0.05);
    for (int it = 0; it < 5000; ++it) {
        for (size_t k = 0; k < 4; ++k) g[k] = 2 * c[k] * (p[k] - m[k]);
        if (it == 3000) adam.setLearningRate(0.005);
        adam.step(p, g);
    }
    for (size_t k = 0; k < 4; ++k) EXPECT_NEAR(p[k], m[k], 1e-3) << k;
}

// A student network trained on the outputs of a random teacher of the same
// architecture (the T network's 3-7-7-1 with sigmoid, on unit vectors) gets
// the teacher's function back.
TEST(Mlp, RecoversAKnownNetwork) {
    // Weights scaled up so that the teacher's output spans much of (0, 1).
    Mlp<float> teacher({3, 7, 7, 1}, OutputFunction::Sigmoid, 11);
    for (float& p : teacher.parameters()) p *= 4.0f;
    Mlp<float> student({3, 7, 7, 1}, OutputFunction::Sigmoid, 12);
    Rng rng(3, 3);
    auto unitVectors = [&](int n) {
        Mlp<float>::Matrix x(3, n);
        for (int c = 0; c < n; ++c) {
            const double z = rng.uniform(), phi = 6.283185307179586 * rng.uniform();
            const double s = std::sqrt(1 - z * z);
            x(0, c) = static_cast<float>(s * std::cos(phi));
            x(1, c) = static_cast<float>(s * std::sin(phi));
            x(2, c) = static_cast<float>(z);
        }
        return x;
    };
    const Mlp<float>::Matrix test = unitVectors(2000), testTarget = teacher.forward(test);
    const double spread = std::sqrt((testTarget.array() - testTarget.mean()).square().mean());
    Adam<float> adam(student.parameters().size(), 1e-2);
    std::vector<float> grad;
    const int steps = static_cast<int>(testing::scaled(6000));
    for (int it = 0; it < steps; ++it) {
        if (it == steps / 2) adam.setLearningRate(3e-3);
        if (it == 5 * steps / 6) adam.setLearningRate(1e-3);
        const Mlp<float>::Matrix x = unitVectors(256);
        student.lossAndGradient(x, teacher.forward(x), Loss::Mse, {}, grad);
        adam.step(student.parameters(), grad);
    }
    const double rmse = std::sqrt((student.forward(test) - testTarget).array().square().mean());
    std::printf("teacher-student: rmse %.3g, target spread %.3g\n", rmse, spread);
    EXPECT_GT(spread, 0.1);
    EXPECT_LT(rmse, 0.03 * spread);
}

TEST(Mlp, RejectsBadArchitectures) {
    testing::expectInputError([] { Mlp<float>({3}, OutputFunction::Exp, 0); }, {"at least"});
    testing::expectInputError([] { Mlp<float>({3, 0, 1}, OutputFunction::Exp, 0); },
                              {"width 0", "[1, 4096]"});
}

}  // namespace
}  // namespace weft
