// bench/mlp — training and inference throughput of the yarn networks
// (Google Benchmark). Reports samples/s (items_per_second) for one Adam step
// on a mini-batch (forward + backward + update) and for a forward pass, for
// the T network 3-7-7-1 and the M networks 6-21-21-3 and 6-21-21-21-3.
// Run: build/release/bench_mlp [--benchmark_out=bench/results/mlp.json --benchmark_out_format=json]
#include <benchmark/benchmark.h>

#include "weft/core/rng.h"
#include "weft/fit/mlp.h"

using namespace weft;

namespace {

std::vector<int> architecture(int id) {
    switch (id) {
        case 0: return {3, 7, 7, 1};
        case 1: return {6, 21, 21, 3};
        default: return {6, 21, 21, 21, 3};
    }
}

Mlp<float>::Matrix randomBatch(int rows, int cols) {
    Rng rng(1, 1);
    Mlp<float>::Matrix m(rows, cols);
    for (int c = 0; c < cols; ++c)
        for (int r = 0; r < rows; ++r) m(r, c) = static_cast<float>(2 * rng.uniform() - 1);
    return m;
}

void TrainStep(benchmark::State& state) {
    const std::vector<int> widths = architecture(static_cast<int>(state.range(0)));
    const int batch = static_cast<int>(state.range(1));
    Mlp<float> net(widths, OutputFunction::Exp, 1);
    Adam<float> adam(net.parameters().size(), 1e-3);
    const auto x = randomBatch(widths.front(), batch);
    const Mlp<float>::Matrix t = randomBatch(widths.back(), batch).array().abs().matrix();
    std::vector<float> grad;
    for (auto _ : state) {
        net.lossAndGradient(x, t, Loss::LogMse, {}, grad);
        adam.step(net.parameters(), grad);
    }
    state.SetItemsProcessed(state.iterations() * batch);
}

void Forward(benchmark::State& state) {
    const std::vector<int> widths = architecture(static_cast<int>(state.range(0)));
    const int batch = static_cast<int>(state.range(1));
    const Mlp<float> net(widths, OutputFunction::Exp, 1);
    const auto x = randomBatch(widths.front(), batch);
    for (auto _ : state) benchmark::DoNotOptimize(net.forward(x));
    state.SetItemsProcessed(state.iterations() * batch);
}

}  // namespace

// Arguments: architecture (0: 3-7-7-1, 1: 6-21-21-3, 2: 6-21-21-21-3), batch size.
BENCHMARK(TrainStep)->ArgsProduct({{0, 1, 2}, {256, 1024}});
BENCHMARK(Forward)->ArgsProduct({{0, 1, 2}, {1024}});
BENCHMARK_MAIN();
