// FixedMlp's SIMD kernels (every instruction set this CPU runs) against its
// scalar reference, and the scalar reference against a plain double-precision
// evaluation of the NetworkWeights, on the shipped models and on random
// networks whose widths are not multiples of any vector width.
#include "weft/yarn/fixed_mlp.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "weft/core/json_file.h"
#include "weft/core/rng.h"
#include "weft/yarn/family_model.h"
#include "weft/yarn/yarn_model.h"

namespace weft {
namespace {

using WideMlp = FixedMlp<64, 16384>;

// The network in double precision, straight from the weights (row-major W,
// bias, PReLU slopes, output function): the independent reference.
std::vector<double> evalDouble(const NetworkWeights& net, const std::vector<float>& x) {
    std::vector<double> a(x.begin(), x.end());
    for (const NetworkLayer& layer : net.layers) {
        std::vector<double> z(layer.out);
        for (int o = 0; o < layer.out; ++o) {
            double sum = layer.bias[o];
            for (int j = 0; j < layer.in; ++j) sum += double(layer.w(o, j)) * a[j];
            if (layer.hasPrelu()) sum = std::max(sum, 0.0) + layer.prelu[o] * std::min(sum, 0.0);
            z[o] = sum;
        }
        a = std::move(z);
    }
    for (double& y : a) {
        if (net.output == OutputFunction::Sigmoid) y = 1 / (1 + std::exp(-y));
        if (net.output == OutputFunction::Exp) y = std::exp(std::min(y, 80.0));
    }
    return a;
}

// Relative difference, with a floor for values near 0: for exp and sigmoid
// outputs 1e-3 (a P(T) or an RGB value of S_M below 1e-3 is held to 1e-8
// absolute at a 1e-5 tolerance; a P(T) of 1e-6 is the sigmoid of a
// pre-activation near -14 whose float rounding is its relative error), for
// identity outputs 1 (their size is set by the sums that cancel to give them,
// not by the value).
double difference(double got, double want, OutputFunction output) {
    const double floor = output == OutputFunction::Identity ? 1.0 : 1e-3;
    return std::fabs(got - want) / std::max(std::fabs(want), floor);
}

// Inputs: unit directions as the BSDF passes them ((wi, wo) for six inputs,
// wi for three; wi in the upper hemisphere, where YarnBsdf mirrors it) for
// every input when `directions`, else for every other one, the others
// uniform values in [-3, 3].
std::vector<std::vector<float>> randomInputs(int inputs, int count, uint64_t seed,
                                             bool directions = false) {
    Rng rng(seed, 5);
    auto unit = [&] {
        const double z = 1 - 2 * rng.uniform(), phi = 6.283185307179586 * rng.uniform();
        const double r = std::sqrt(std::max(0.0, 1 - z * z));
        return std::vector<double>{r * std::cos(phi), r * std::sin(phi), z};
    };
    std::vector<std::vector<float>> xs;
    for (int c = 0; c < count; ++c) {
        std::vector<float> x(inputs);
        if ((directions || c % 2 == 0) && inputs % 3 == 0) {
            for (int k = 0; k < inputs; k += 3) {
                std::vector<double> w = unit();
                if (k == 0) w[2] = std::fabs(w[2]);  // wi in the upper hemisphere
                for (int i = 0; i < 3; ++i) x[k + i] = static_cast<float>(w[i]);
            }
        } else {
            for (float& v : x) v = static_cast<float>(6 * rng.uniform() - 3);
        }
        xs.push_back(x);
    }
    return xs;
}

// The largest difference of forward() from forwardScalar() over `xs`; also
// checks that forward() writes outputs() values and nothing after them.
// The tolerance of forward() against forwardScalar(): 1e-5 relative. A
// kernel without fused multiply-adds (SSSE3, SSE4, the portable fallback:
// only CPUs without AVX2 run them) rounds every product as well, and the
// shipped networks' large cancelling sums take it to about 1.2e-5: 2e-5.
double tolerance(const FixedMlpKernel& kernel) { return kernel.fusedMultiplyAdd ? 1e-5 : 2e-5; }

template <int W, int C>
double largestSimdDifference(const FixedMlp<W, C>& net,
                             const std::vector<std::vector<float>>& xs) {
    double worst = 0;
    const int n = net.outputs();
    std::vector<float> simd(n + 1), scalar(n);
    for (const std::vector<float>& x : xs) {
        simd[n] = -7.0f;
        net.forward(x.data(), simd.data());
        net.forwardScalar(x.data(), scalar.data());
        EXPECT_EQ(simd[n], -7.0f) << "forward wrote past its outputs";
        for (int o = 0; o < n; ++o)
            worst = std::max(worst, difference(simd[o], scalar[o], net.output()));
    }
    return worst;
}

template <int W, int C>
double largestScalarDifference(const FixedMlp<W, C>& net, const NetworkWeights& weights,
                               const std::vector<std::vector<float>>& xs) {
    double worst = 0;
    std::vector<float> y(net.outputs());
    for (const std::vector<float>& x : xs) {
        net.forwardScalar(x.data(), y.data());
        const std::vector<double> want = evalDouble(weights, x);
        for (int o = 0; o < net.outputs(); ++o)
            worst = std::max(worst, difference(y[o], want[o], weights.output));
    }
    return worst;
}

// Random PReLU slopes (some negative, some above 1) so that both sides matter.
NetworkWeights randomNetwork(const std::vector<int>& widths, OutputFunction output,
                             uint64_t seed) {
    NetworkWeights net = NetworkWeights::initialised(widths, output, seed);
    Rng rng(seed, 99);
    for (NetworkLayer& layer : net.layers)
        for (float& slope : layer.prelu) slope = static_cast<float>(1.6 * rng.uniform() - 0.3);
    return net;
}

std::vector<std::string> shippedModels() {
    std::vector<std::string> paths;
    for (const auto& entry :
         std::filesystem::directory_iterator(std::string(WEFT_SOURCE_DIR) + "/models"))
        if (entry.path().extension() == ".json") paths.push_back(entry.path().string());
    std::sort(paths.begin(), paths.end());
    return paths;
}

TEST(FixedMlp, KernelsForThisCpu) {
    const std::vector<FixedMlpKernel> kernels = fixedMlpKernels();
    ASSERT_FALSE(kernels.empty());
    EXPECT_STREQ(kernels.front().target, fixedMlpKernel().target);
    std::string names;
    for (const FixedMlpKernel& k : kernels) {
        EXPECT_NE(k.forward, nullptr) << k.target;
        EXPECT_GE(k.lanes, 1) << k.target;
        EXPECT_LE(k.lanes, FixedMlpKernel::kMaxLanes) << k.target;
        names += std::string(names.empty() ? "" : ", ") + k.target + " (" +
                 std::to_string(k.lanes) + " lanes)";
    }
    // Listing the kernels leaves the dispatch at the best one.
    EXPECT_STREQ(fixedMlpKernel().target, kernels.front().target);
    const ScatteringMlp net(NetworkWeights::initialised({6, 21, 3}, OutputFunction::Exp, 1), "m");
    EXPECT_STREQ(net.target(), kernels.front().target);
    std::printf("FixedMlp kernels on this CPU, best first: %s\n", names.c_str());
}

TEST(FixedMlp, SimdMatchesScalarOnShippedModels) {
    const std::vector<std::string> paths = shippedModels();
    EXPECT_GE(paths.size(), 5u);
    for (const std::string& path : paths) {
        // The family model (family_model.h) by its yarn at the box's centre.
        const nlohmann::json document = readJsonFile(path);
        const YarnModel model = isFamilyModelDocument(document)
                                    ? familyModelFromJson(document, path)
                                          .at(familyModelFromJson(document, path).centre(), path)
                                    : yarnModelFromJson(document, path);
        // The trained networks' domain: wi in the upper hemisphere, wo on the
        // sphere. Outside it (wi.z < 0, which YarnBsdf never passes) some
        // shipped T networks sum hidden values of 1e3 to a pre-activation
        // near 0, and float32 rounding alone (any order) moves P(T) by 1e-4.
        const auto tInputs = randomInputs(3, 4000, 1, true), mInputs = randomInputs(6, 4000, 2, true);
        for (const FixedMlpKernel& kernel : fixedMlpKernels()) {
            const TransmissionMlp t(model.tNet, "t_net", kernel);
            const ScatteringMlp m(model.mNet, "m_net", kernel);
            const double dt = largestSimdDifference(t, tInputs);
            const double dm = largestSimdDifference(m, mInputs);
            EXPECT_LE(dt, tolerance(kernel)) << path << " t_net " << kernel.target;
            EXPECT_LE(dm, tolerance(kernel)) << path << " m_net " << kernel.target;
            std::printf("%s %s: largest relative difference t_net %.2g, m_net %.2g\n",
                        std::filesystem::path(path).filename().c_str(), kernel.target, dt, dm);
        }
        EXPECT_LE(largestScalarDifference(TransmissionMlp(model.tNet, "t_net"), model.tNet, tInputs),
                  1e-5)
            << path;
        EXPECT_LE(largestScalarDifference(ScatteringMlp(model.mNet, "m_net"), model.mNet, mInputs),
                  1e-5)
            << path;
    }
}

TEST(FixedMlp, SimdMatchesScalarOnRandomNetworks) {
    struct Case {
        std::vector<int> widths;
        OutputFunction output;
    };
    // Widths around and between the vector widths (4, 8, 16 floats), depths 1 to 8.
    const std::vector<Case> cases = {
        {{3, 7, 7, 1}, OutputFunction::Sigmoid},
        {{6, 21, 21, 21, 3}, OutputFunction::Exp},
        {{6, 21, 21, 3}, OutputFunction::Exp},
        {{6, 64, 64, 3}, OutputFunction::Exp},
        {{6, 1, 9, 3}, OutputFunction::Identity},
        {{6, 3}, OutputFunction::Exp},
        {{1, 1}, OutputFunction::Identity},
        {{5, 17, 33, 2}, OutputFunction::Identity},
        {{9, 40, 13, 5}, OutputFunction::Sigmoid},
        {{6, 31, 49, 63, 7}, OutputFunction::Exp},
        {{2, 4, 8, 16, 32, 48, 64, 15, 3}, OutputFunction::Identity},
        {{3, 5, 9, 11, 13, 15, 17, 19, 1}, OutputFunction::Sigmoid},
        {{64, 12, 4}, OutputFunction::Exp},
    };
    for (size_t c = 0; c < cases.size(); ++c) {
        const NetworkWeights weights = randomNetwork(cases[c].widths, cases[c].output, 20 + c);
        const auto xs = randomInputs(weights.inputs(), 1000, 30 + c);
        for (const FixedMlpKernel& kernel : fixedMlpKernels()) {
            const WideMlp net(weights, "net", kernel);
            ASSERT_EQ(net.inputs(), cases[c].widths.front());
            ASSERT_EQ(net.outputs(), cases[c].widths.back());
            EXPECT_LE(largestSimdDifference(net, xs), tolerance(kernel))
                << weights.widthsText() << " " << kernel.target;
        }
        EXPECT_LE(largestScalarDifference(WideMlp(weights, "net"), weights, xs), 1e-5)
            << weights.widthsText();
    }
}

// forwardBatch runs lanes() queries per kernel call, one per lane; each
// query's outputs must be forward()'s bits whatever the batch's size (partial
// batches: lanes whose paths have ended are zero-filled) and whichever lane it
// lands in, and so within forward()'s tolerance of the scalar reference; it
// writes count x outputs() values and nothing after them.
TEST(FixedMlp, BatchGivesForwardsBitsInEveryLane) {
    for (const auto& widths : std::vector<std::vector<int>>{{6, 21, 21, 21, 3},
                                                            {3, 7, 7, 1},
                                                            {6, 21, 21, 3},
                                                            {6, 64, 64, 3},
                                                            {5, 17, 33, 49, 2},
                                                            {1, 1},
                                                            {64, 12, 4}}) {
        for (const OutputFunction output :
             {OutputFunction::Exp, OutputFunction::Sigmoid, OutputFunction::Identity}) {
            const NetworkWeights weights = randomNetwork(widths, output, 7);
            const int in = weights.inputs(), out = weights.outputs();
            const auto xs = randomInputs(in, 200, 8);
            std::vector<float> flat;
            for (const auto& x : xs) flat.insert(flat.end(), x.begin(), x.end());
            for (const FixedMlpKernel& kernel : fixedMlpKernels()) {
                const WideMlp net(weights, "net", kernel);
                const int lanes = net.lanes();
                for (const int offset : {0, 1, lanes - 1}) {
                    for (const int count : {1, lanes - 1, lanes, lanes + 1, 3 * lanes + 5, 150}) {
                        if (count < 1) continue;
                        std::vector<float> batch(count * out + 1, -7.0f);
                        net.forwardBatch(flat.data() + offset * in, count, batch.data());
                        ASSERT_EQ(batch.back(), -7.0f) << "forwardBatch wrote past its outputs";
                        std::vector<float> one(out), scalar(out);
                        for (int k = 0; k < count; ++k) {
                            const float* x = flat.data() + (offset + k) * in;
                            net.forward(x, one.data());
                            net.forwardScalar(x, scalar.data());
                            for (int o = 0; o < out; ++o) {
                                ASSERT_EQ(batch[k * out + o], one[o])
                                    << weights.widthsText() << " " << kernel.target << " query "
                                    << k << " of " << count << " output " << o;
                                EXPECT_LE(difference(batch[k * out + o], scalar[o], output),
                                          tolerance(kernel))
                                    << weights.widthsText() << " " << kernel.target;
                            }
                        }
                    }
                }
            }
        }
    }
}

// Every kernel with FMA does the same operations per output in the same
// order: AVX2 and AVX-512 give the same bits, so a render does not depend on
// which of them the CPU has.
TEST(FixedMlp, KernelsWithFmaAgreeBitForBit) {
    std::vector<FixedMlpKernel> fma;
    for (const FixedMlpKernel& kernel : fixedMlpKernels())
        if (kernel.fusedMultiplyAdd) fma.push_back(kernel);
    if (fma.size() < 2) GTEST_SKIP() << "fewer than two kernels with FMA on this CPU";
    for (const auto& widths : std::vector<std::vector<int>>{
             {6, 21, 21, 21, 3}, {3, 7, 7, 1}, {6, 64, 64, 3}, {5, 17, 33, 49, 2}}) {
        const NetworkWeights weights = randomNetwork(widths, OutputFunction::Exp, 3);
        const auto xs = randomInputs(weights.inputs(), 500, 4);
        const WideMlp reference(weights, "net", fma.front());
        std::vector<float> want(weights.outputs()), got(weights.outputs());
        for (size_t k = 1; k < fma.size(); ++k) {
            const WideMlp net(weights, "net", fma[k]);
            for (const std::vector<float>& x : xs) {
                reference.forward(x.data(), want.data());
                net.forward(x.data(), got.data());
                ASSERT_EQ(got, want) << weights.widthsText() << " " << fma[k].target;
            }
        }
    }
}

// The kernels pad each layer to their own vector width; whether a network
// fits must not depend on it (capacity is checked at the widest padding).
TEST(FixedMlp, CapacityDoesNotDependOnTheKernel) {
    // 6-21-21-21-3 at 16-float padding: 32 (6+2) + 2 * 32 (21+2) + 16 (21+1) = 2080 floats.
    const NetworkWeights net = NetworkWeights::initialised({6, 21, 21, 21, 3}, OutputFunction::Exp, 1);
    for (const FixedMlpKernel& kernel : fixedMlpKernels()) {
        EXPECT_NO_THROW((FixedMlp<32, 2080>(net, "m_net", kernel))) << kernel.target;
        EXPECT_THROW((FixedMlp<32, 2079>(net, "m_net", kernel)), InputError) << kernel.target;
    }
}

TEST(FixedMlp, DefaultConstructedEvaluatorIsInert) {
    const TransmissionMlp net;
    float y = 3;
    const float x[3] = {0, 0, 1};
    net.forward(x, &y);
    EXPECT_EQ(y, 3);
    EXPECT_EQ(net.outputs(), 0);
}

}  // namespace
}  // namespace weft
