// bench/mlp — training and inference throughput of the yarn networks
// (Google Benchmark). Reports samples/s (items_per_second) for one Adam step
// on a mini-batch (forward + backward + update) and for a forward pass, for
// the T network 3-7-7-1, the M networks 6-21-21-3 and 6-21-21-21-3, and a
// 13-32-32-32-3 network (the M inputs and 7 yarn parameters: the size a
// family model may need). TrainStep is Mlp::lossAndGradient (Eigen, the
// reference form); BatchedTrainStep is what weft fit runs (fit/train.cpp):
// the batch in 8 chunks of MlpBatch passes on a task arena of 1 or 2
// threads, their gradients summed in order, one Adam step.
// Run: build/release/bench_mlp [--benchmark_out=bench/results/mlp.json --benchmark_out_format=json]
// (bench/trainer.py runs it beside PyTorch on the same networks).
#include "weft/fit/mlp.h"

#include <benchmark/benchmark.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "weft/core/rng.h"
#include "weft/fit/mlp_batch.h"

using namespace weft;

namespace {

std::vector<int> architecture(int id) {
    switch (id) {
        case 0: return {3, 7, 7, 1};
        case 1: return {6, 21, 21, 3};
        case 2:
            return {6, 21, 21, 21, 3};
        default:
            return {13, 32, 32, 32, 3};
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

void BatchedTrainStep(benchmark::State& state) {
    constexpr int kChunks = 8;
    const std::vector<int> widths = architecture(static_cast<int>(state.range(0)));
    const int batch = static_cast<int>(state.range(1));
    tbb::task_arena arena(static_cast<int>(state.range(2)));
    Mlp<float> net(widths, OutputFunction::Exp, 1);
    Adam<float> adam(net.parameters().size(), 1e-3);
    const int chunk = batch / kChunks;
    Rng rng(1, 1);
    std::vector<BatchRows> x, t;
    std::vector<MlpBatch> passes;
    for (int c = 0; c < kChunks; ++c) {
        x.emplace_back(widths.front(), chunk);
        t.emplace_back(widths.back(), chunk);
        passes.emplace_back(net, chunk);
        for (int k = 0; k < chunk; ++k) {
            for (int r = 0; r < widths.front(); ++r)
                x[c](r, k) = static_cast<float>(2 * rng.uniform() - 1);
            for (int r = 0; r < widths.back(); ++r) t[c](r, k) = static_cast<float>(rng.uniform());
        }
    }
    std::vector<std::vector<float>> grad(kChunks);
    std::vector<float> total(net.parameters().size());
    for (auto _ : state) {
        arena.execute([&] {
            tbb::parallel_for(0, kChunks, [&](int c) {
                passes[c].lossAndGradient(x[c], t[c], chunk, Loss::LogMse, grad[c]);
            });
        });
        std::fill(total.begin(), total.end(), 0.0f);
        for (int c = 0; c < kChunks; ++c)
            for (size_t k = 0; k < total.size(); ++k) total[k] += grad[c][k] / kChunks;
        adam.step(net.parameters(), total);
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

// Arguments: architecture (0: 3-7-7-1, 1: 6-21-21-3, 2: 6-21-21-21-3,
// 3: 13-32-32-32-3), batch size (, threads).
BENCHMARK(TrainStep)->ArgsProduct({{0, 1, 2, 3}, {256, 1024}});
BENCHMARK(BatchedTrainStep)->ArgsProduct({{0, 1, 2, 3}, {512, 1024}, {1, 2}})->UseRealTime();
BENCHMARK(Forward)->ArgsProduct({{0, 1, 2, 3}, {1024}});
BENCHMARK_MAIN();
