// bench/bsdf — cost of one yarn BSDF query against the fiber BCSDF (Google Benchmark).
//
// ns per call (per query for the batched networks), one thread, on 4096 fixed random direction
// pairs (wi in the upper hemisphere, wo on the sphere) cycled through so that branches and caches
// see a renderer-like mix: YarnBsdf eval / pdf / sample (with and without the energy guard), the
// same on a prepared incident (Bsdf::prepare once per wi outside the timing, then eval / evalPdf /
// sample(in, ...): the per-wo cost that a path tracer pays at a shading point), prepare alone and
// one whole path vertex (prepare, NEE's evalPdf, sample) of each model, its parts (the T
// and M networks through FixedMlp, SIMD kernel and scalar reference, the R
// lobe), Mlp<float>::forward on a batch of one (what the fixed-size evaluator
// replaces), FiberBcsdf eval / sample, and the time to construct a YarnBsdf
// (model validation, energy guard table); the dual-scattering baseline
// (yarn/dual_scattering.h) for the model's fiber and ply: the same per-wo
// costs and its construction (energy clamp table).
// Writes a Markdown table (default bench/results/bsdf.md; --md=PATH) with
// every time relative to FiberBcsdf::eval; --benchmark_out=FILE.json adds
// Google Benchmark's JSON. The model: tests/data/fleece-small.json next to
// this file, or --model=PATH. On a shared machine use repetitions:
//     build/release/bench_bsdf --benchmark_repetitions=9 --benchmark_min_time=0.2
//         --benchmark_enable_random_interleaving=true
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "weft/core/file.h"
#include "weft/core/math.h"
#include "weft/core/rng.h"
#include "weft/fiber/fiber_bcsdf.h"
#include "weft/fit/mlp.h"
#include "weft/yarn/dual_scattering.h"
#include "weft/yarn/yarn_bsdf.h"

using namespace weft;

namespace {

std::string gModelPath =
    (std::filesystem::path(__FILE__).parent_path() / ".." / "tests" / "data" / "fleece-small.json")
        .lexically_normal()
        .string();

const YarnModel& model() {
    static const YarnModel m = loadYarnModel(gModelPath);
    return m;
}
const YarnBsdf& guardedBsdf() {
    static const YarnBsdf b(model(), gModelPath);
    return b;
}
const YarnBsdf& rawBsdf() {
    static const YarnBsdf b(model(), gModelPath, YarnBsdfOptions{false});
    return b;
}
// With the paper's sampling (eq. 9-11) instead of the tabulated default.
const YarnBsdf& fittedBsdf() {
    static const YarnBsdf b(model(), gModelPath, YarnBsdfOptions{true, YarnSampling::Fitted});
    return b;
}

// The dual-scattering baseline of the same fiber and ply (render --mode dual).
const DualScatteringBsdf& dualBsdf() {
    static const DualScatteringBsdf b(model().fiber, model().ply);
    return b;
}

constexpr size_t kPairs = 4096;

struct Pairs {
    std::vector<Vec3> wi, wo;
    std::vector<BsdfSampleInput> u;
};

const Pairs& pairs() {
    static const Pairs p = [] {
        Pairs p;
        Rng rng(1, 2);
        auto unit = [&] {
            const double z = 1 - 2 * rng.uniform(), phi = kTwoPi * rng.uniform();
            const double r = std::sqrt(std::max(0.0, 1 - z * z));
            return Vec3{r * std::cos(phi), r * std::sin(phi), z};
        };
        for (size_t k = 0; k < kPairs; ++k) {
            Vec3 wi = unit();
            wi.z = std::fabs(wi.z);
            p.wi.push_back(wi);
            p.wo.push_back(unit());
            p.u.push_back({rng.uniform(), rng.uniform(), rng.uniform()});
        }
        return p;
    }();
    return p;
}

// The pairs' wi prepared once (outside the timing), as a path tracer does at a
// shading point before it evaluates and samples there.
const std::vector<BsdfIncident>& preparedIncidents(const Bsdf& bsdf) {
    static std::vector<std::pair<const Bsdf*, std::vector<BsdfIncident>>> cache;
    for (const auto& [b, incidents] : cache)
        if (b == &bsdf) return incidents;
    std::vector<BsdfIncident> incidents(kPairs);
    for (size_t k = 0; k < kPairs; ++k) bsdf.prepare(pairs().wi[k], incidents[k]);
    cache.emplace_back(&bsdf, std::move(incidents));
    return cache.back().second;
}

// The networks' inputs as floats: (wi, wo) per pair.
const std::vector<std::array<float, 6>>& floatPairs() {
    static const std::vector<std::array<float, 6>> x = [] {
        std::vector<std::array<float, 6>> x;
        for (size_t k = 0; k < kPairs; ++k) {
            const Vec3 &wi = pairs().wi[k], &wo = pairs().wo[k];
            x.push_back({static_cast<float>(wi.x), static_cast<float>(wi.y),
                         static_cast<float>(wi.z), static_cast<float>(wo.x),
                         static_cast<float>(wo.y), static_cast<float>(wo.z)});
        }
        return x;
    }();
    return x;
}

const ScatteringMlp& mNet() {
    static const ScatteringMlp net(model().mNet, "m_net");
    return net;
}
const TransmissionMlp& tNet() {
    static const TransmissionMlp net(model().tNet, "t_net");
    return net;
}

template <typename F>
void loop(benchmark::State& state, const F& f) {
    const Pairs& p = pairs();
    size_t k = 0;
    for (auto _ : state) {
        f(p.wi[k], p.wo[k], p.u[k]);
        k = (k + 1) % kPairs;
    }
    state.SetItemsProcessed(state.iterations());
}

void FiberEval(benchmark::State& state) {
    const FiberBcsdf fiber(model().fiber);
    loop(state, [&](const Vec3& wi, const Vec3& wo, const BsdfSampleInput&) {
        benchmark::DoNotOptimize(fiber.eval(wi, wo));
    });
}

void FiberEvalPrepared(benchmark::State& state) {
    const FiberBcsdf fiber(model().fiber);
    const std::vector<BsdfIncident>& in = preparedIncidents(fiber);
    const Pairs& p = pairs();
    size_t k = 0;
    for (auto _ : state) {
        benchmark::DoNotOptimize(fiber.eval(in[k], p.wo[k]));
        k = (k + 1) % kPairs;
    }
    state.SetItemsProcessed(state.iterations());
}

void FiberSample(benchmark::State& state) {
    const FiberBcsdf fiber(model().fiber);
    loop(state, [&](const Vec3& wi, const Vec3&, const BsdfSampleInput& u) {
        benchmark::DoNotOptimize(fiber.sample(wi, u));
    });
}

void YarnEval(benchmark::State& state) {
    const YarnBsdf& bsdf = state.range(0) ? guardedBsdf() : rawBsdf();
    loop(state, [&](const Vec3& wi, const Vec3& wo, const BsdfSampleInput&) {
        benchmark::DoNotOptimize(bsdf.eval(wi, wo));
    });
}

void YarnPdf(benchmark::State& state) {
    const YarnBsdf& bsdf = guardedBsdf();
    loop(state, [&](const Vec3& wi, const Vec3& wo, const BsdfSampleInput&) {
        benchmark::DoNotOptimize(bsdf.pdf(wi, wo));
    });
}

void YarnSample(benchmark::State& state) {
    const YarnBsdf& bsdf = state.range(0) ? guardedBsdf() : rawBsdf();
    loop(state, [&](const Vec3& wi, const Vec3&, const BsdfSampleInput& u) {
        benchmark::DoNotOptimize(bsdf.sample(wi, u));
    });
}

// eval, evalPdf or sample on a prepared incident (argument 0, 1, 2), with the
// energy guard; sample draws its rejection steps from one running generator,
// as a path's own.
// Argument 0: eval, 1: evalPdf, 2: sample; argument 1: tabulated (1) or fitted (0) sampling.
// eval (what 0), evalPdf (1) or sample (2) of `bsdf` on the prepared pairs.
void preparedCalls(benchmark::State& state, const Bsdf& bsdf, int64_t what) {
    const std::vector<BsdfIncident>& in = preparedIncidents(bsdf);
    const Pairs& p = pairs();
    Rng rng(3, 4);
    size_t k = 0;
    for (auto _ : state) {
        if (what == 0)
            benchmark::DoNotOptimize(bsdf.eval(in[k], p.wo[k]));
        else if (what == 1)
            benchmark::DoNotOptimize(bsdf.evalPdf(in[k], p.wo[k]));
        else
            benchmark::DoNotOptimize(bsdf.sample(in[k], p.u[k], rng));
        k = (k + 1) % kPairs;
    }
    state.SetItemsProcessed(state.iterations());
}

void YarnPrepared(benchmark::State& state) {
    preparedCalls(state, state.range(1) != 0 ? guardedBsdf() : fittedBsdf(), state.range(0));
}

// The batches of core/bsdf.h on 256 prepared pairs per call (argument 0:
// evalPdfBatch, 1: sampleBatch, 2: prepareBatch), as the batched path
// tracer calls them; time per query.
void YarnBatch(benchmark::State& state) {
    constexpr size_t kBatch = 256;
    const YarnBsdf& bsdf = guardedBsdf();
    const std::vector<BsdfIncident>& prepared = preparedIncidents(bsdf);
    const Pairs& p = pairs();
    std::vector<BsdfIncident> scratch(kBatch);
    std::vector<const BsdfIncident*> in(kBatch);
    std::vector<BsdfIncident*> out(kBatch);
    std::vector<Rng> rngs(kBatch, Rng(3, 4));
    std::vector<Rng*> rng(kBatch);
    for (size_t k = 0; k < kBatch; ++k) rng[k] = &rngs[k], out[k] = &scratch[k];
    std::vector<BsdfEval> evals(kBatch);
    std::vector<BsdfSample> samples(kBatch);
    size_t first = 0;
    for (auto _ : state) {
        for (size_t k = 0; k < kBatch; ++k) in[k] = &prepared[first + k];
        if (state.range(0) == 0)
            bsdf.evalPdfBatch(in.data(), &p.wo[first], kBatch, evals.data());
        else if (state.range(0) == 1)
            bsdf.sampleBatch(in.data(), &p.u[first], rng.data(), kBatch, samples.data());
        else
            bsdf.prepareBatch(&p.wi[first], out.data(), kBatch);
        benchmark::DoNotOptimize(evals.data());
        benchmark::DoNotOptimize(samples.data());
        benchmark::DoNotOptimize(scratch.data());
        first = (first + kBatch) % (kPairs - kBatch);
    }
    state.SetItemsProcessed(state.iterations() * kBatch);
    state.counters["queries"] = kBatch;  // the table divides the time per call by it
}

// Bsdf::prepare alone (what depends on wi: P(T), the calibration, the guard,
// the sampling table's rows and nodes).
void Prepare(benchmark::State& state, const Bsdf& bsdf) {
    BsdfIncident in;
    loop(state, [&](const Vec3& wi, const Vec3&, const BsdfSampleInput&) {
        bsdf.prepare(wi, in);
        benchmark::DoNotOptimize(in);
    });
}

// One path vertex with next-event estimation: prepare(wi), evalPdf towards
// the light (wo) and sample() of the next direction, the calls a path tracer
// makes per bounce; the ratio of the yarn's to the fiber's is what a neural
// render pays per vertex against a fiber render.
void Vertex(benchmark::State& state, const Bsdf& bsdf) {
    BsdfIncident in;
    Rng rng(3, 4);
    loop(state, [&](const Vec3& wi, const Vec3& wo, const BsdfSampleInput& u) {
        bsdf.prepare(wi, in);
        benchmark::DoNotOptimize(bsdf.evalPdf(in, wo));
        benchmark::DoNotOptimize(bsdf.sample(in, u, rng));
    });
}

const FiberBcsdf& fiberBcsdf() {
    static const FiberBcsdf f(model().fiber);
    return f;
}
void FiberPrepare(benchmark::State& state) { Prepare(state, fiberBcsdf()); }
void YarnPrepare(benchmark::State& state) { Prepare(state, guardedBsdf()); }
void FiberVertex(benchmark::State& state) { Vertex(state, fiberBcsdf()); }
void YarnVertex(benchmark::State& state) { Vertex(state, guardedBsdf()); }

// The same three calls of the dual-scattering baseline on a prepared incident.
void DualPrepared(benchmark::State& state) { preparedCalls(state, dualBsdf(), state.range(0)); }

// FixedMlp::forward (argument 1: the SIMD kernel) or forwardScalar (0) on
// float inputs: the network alone, without the conversion from Vec3.
void MNetwork(benchmark::State& state) {
    const ScatteringMlp& net = mNet();
    const auto& x = floatPairs();
    const bool simd = state.range(0) != 0;
    float y[3];
    size_t k = 0;
    for (auto _ : state) {
        if (simd)
            net.forward(x[k].data(), y);
        else
            net.forwardScalar(x[k].data(), y);
        benchmark::DoNotOptimize(y);
        k = (k + 1) % kPairs;
    }
    state.SetItemsProcessed(state.iterations());
}

// A batch of state.range(0) queries per call (FixedMlp::forwardBatch, one
// query per SIMD lane), from consecutive pairs; time per query.
template <typename Net>
void networkBatch(benchmark::State& state, const Net& net) {
    const int count = static_cast<int>(state.range(0));
    const int in = net.inputs(), out = net.outputs();
    std::vector<float> x, y(static_cast<size_t>(count) * out);
    for (size_t k = 0; k < kPairs; ++k)
        x.insert(x.end(), floatPairs()[k].begin(), floatPairs()[k].begin() + in);
    size_t first = 0;
    for (auto _ : state) {
        net.forwardBatch(x.data() + first * in, count, y.data());
        benchmark::DoNotOptimize(y.data());
        first = (first + count) % (kPairs - count);
    }
    state.SetItemsProcessed(state.iterations() * count);
    state.counters["queries"] = count;  // the table divides the time per call by it
}
void MNetworkBatch(benchmark::State& state) { networkBatch(state, mNet()); }
void TNetworkBatch(benchmark::State& state) { networkBatch(state, tNet()); }

void TNetwork(benchmark::State& state) {
    const TransmissionMlp& net = tNet();
    const auto& x = floatPairs();
    const bool simd = state.range(0) != 0;
    float y;
    size_t k = 0;
    for (auto _ : state) {
        if (simd)
            net.forward(x[k].data(), &y);
        else
            net.forwardScalar(x[k].data(), &y);
        benchmark::DoNotOptimize(y);
        k = (k + 1) % kPairs;
    }
    state.SetItemsProcessed(state.iterations());
}

void YarnMNetwork(benchmark::State& state) {
    const YarnBsdf& bsdf = rawBsdf();
    loop(state, [&](const Vec3& wi, const Vec3& wo, const BsdfSampleInput&) {
        benchmark::DoNotOptimize(bsdf.model().evalM(wi, wo));
    });
}

void YarnTNetwork(benchmark::State& state) {
    const YarnBsdf& bsdf = rawBsdf();
    loop(state, [&](const Vec3& wi, const Vec3&, const BsdfSampleInput&) {
        benchmark::DoNotOptimize(bsdf.transmission(wi));
    });
}

void YarnRLobe(benchmark::State& state) {
    const RLobe& lobe = rawBsdf().model().rLobe();
    loop(state, [&](const Vec3& wi, const Vec3& wo, const BsdfSampleInput&) {
        benchmark::DoNotOptimize(lobe.eval(wi, wo, 0.1));
    });
}

// What FixedMlp replaces: the training code's forward pass on one column.
void MlpForwardBatchOfOne(benchmark::State& state) {
    const Mlp<float> net(model().mNet);
    Mlp<float>::Matrix x(6, 1);
    loop(state, [&](const Vec3& wi, const Vec3& wo, const BsdfSampleInput&) {
        x << static_cast<float>(wi.x), static_cast<float>(wi.y), static_cast<float>(wi.z),
            static_cast<float>(wo.x), static_cast<float>(wo.y), static_cast<float>(wo.z);
        benchmark::DoNotOptimize(net.forward(x));
    });
}

// Argument 2: energy guard and sampling table (the default), 1: the guard
// alone (fitted sampling), 0: neither.
void YarnConstruct(benchmark::State& state) {
    const YarnBsdfOptions options{
        state.range(0) != 0, state.range(0) == 2 ? YarnSampling::Tabulated : YarnSampling::Fitted};
    for (auto _ : state) benchmark::DoNotOptimize(YarnBsdf(model(), gModelPath, options));
}

// Argument 1: with the energy clamp table (the default), 0: without.
void DualConstruct(benchmark::State& state) {
    DualScatteringOptions options;
    options.energyClamp = state.range(0) != 0;
    for (auto _ : state)
        benchmark::DoNotOptimize(DualScatteringBsdf(model().fiber, model().ply, options));
}

// Console output as usual, and every run's CPU time for the Markdown table
// (with --benchmark_repetitions=K, the fastest of the K runs: on a shared
// machine noise only adds time, and random interleaving spreads it).
class TableReporter : public benchmark::ConsoleReporter {
  public:
    struct Row {
        std::string name;
        std::vector<double> nanoseconds;
        double fastest() const {
            return nanoseconds.empty() ? 0.0
                                       : *std::min_element(nanoseconds.begin(), nanoseconds.end());
        }
    };
    std::vector<Row> rows;

    void ReportRuns(const std::vector<Run>& runs) override {
        for (const Run& run : runs) {
            if (run.run_type != Run::RT_Iteration || run.error_occurred) continue;
            const double toNs = 1e9 / benchmark::GetTimeUnitMultiplier(run.time_unit);
            const std::string name = run.benchmark_name();
            auto it = std::find_if(rows.begin(), rows.end(),
                                   [&](const Row& r) { return r.name == name; });
            if (it == rows.end()) it = rows.insert(rows.end(), Row{name, {}});
            const auto queries = run.counters.find("queries");
            const double perCall = queries == run.counters.end() ? 1.0 : queries->second.value;
            it->nanoseconds.push_back(run.GetAdjustedCPUTime() * toNs / perCall);
        }
        ConsoleReporter::ReportRuns(runs);
    }
};

// The table's rows, in this order.
struct Entry {
    const char* name;
    const char* what;
};
const Entry kEntries[] = {
    {"FiberEval", "FiberBcsdf::eval (the reference)"},
    {"FiberEvalPrepared", "FiberBcsdf::eval on a prepared incident"},
    {"FiberSample", "FiberBcsdf::sample"},
    {"YarnEval/1", "YarnBsdf::eval: T network, R lobe, M network, energy guard"},
    {"YarnEval/0", "YarnBsdf::eval without the energy guard"},
    {"YarnPdf", "YarnBsdf::pdf: T network, eq. 10 lobes"},
    {"YarnSample/1", "YarnBsdf::sample: lobe choice, direction, eval and pdf, energy guard"},
    {"YarnSample/0", "YarnBsdf::sample without the energy guard"},
    {"YarnPrepared/0/1", "YarnBsdf::eval on a prepared incident (per-wo cost; target <= 1.2)"},
    {"YarnPrepared/1/1",
     "YarnBsdf::evalPdf on a prepared incident (NEE's eval + pdf; target <= 1.5)"},
    {"YarnPrepared/2/1", "YarnBsdf::sample on a prepared incident (target <= 2)"},
    {"YarnPrepared/0/0", "the same eval, fitted sampling (paper eq. 9-11)"},
    {"YarnPrepared/1/0", "the same evalPdf, fitted sampling"},
    {"YarnPrepared/2/0", "the same sample, fitted sampling"},
    {"YarnBatch/0",
     "YarnBsdf::evalPdfBatch, 256 prepared queries per call (per query; target <= 1.0)"},
    {"YarnBatch/1", "YarnBsdf::sampleBatch, 256 per call (per query; target <= 1.5)"},
    {"YarnBatch/2", "YarnBsdf::prepareBatch, 256 per call (per query)"},
    {"FiberPrepare", "FiberBcsdf::prepare alone"},
    {"YarnPrepare", "YarnBsdf::prepare alone: T network, calibration, guard, table rows and nodes"},
    {"FiberVertex", "one path vertex, fiber: prepare, evalPdf (NEE), sample"},
    {"YarnVertex", "one path vertex, yarn: prepare, evalPdf (NEE), sample"},
    {"YarnMNetwork", "M network alone (evalM: Vec3 in, Rgb out, SIMD kernel)"},
    {"MNetwork/1", "M network alone, FixedMlp::forward on floats (SIMD kernel)"},
    {"MNetwork/0", "M network alone, FixedMlp::forwardScalar on floats (scalar reference)"},
    {"MNetworkBatch/16",
     "M network, FixedMlp::forwardBatch, 16 queries per call (per query; target <= 15 ns)"},
    {"MNetworkBatch/256", "M network, FixedMlp::forwardBatch, 256 queries per call (per query)"},
    {"TNetwork/1", "T network alone, FixedMlp::forward on floats (SIMD kernel)"},
    {"TNetwork/0", "T network alone, FixedMlp::forwardScalar on floats (scalar reference)"},
    {"TNetworkBatch/256", "T network, FixedMlp::forwardBatch, 256 queries per call (per query)"},
    {"YarnTNetwork", "T network alone (transmission: Vec3 in, SIMD kernel)"},
    {"YarnRLobe", "R lobe alone (eq. 8 with masking)"},
    {"MlpForwardBatchOfOne", "M network through Mlp<float>::forward, batch of 1"},
    {"YarnConstruct/2", "YarnBsdf construction: energy guard and sampling table (default)"},
    {"YarnConstruct/1", "YarnBsdf construction with the energy guard table, fitted sampling"},
    {"YarnConstruct/0", "YarnBsdf construction without the guard, fitted sampling"},
    {"DualPrepared/0", "dual-scattering baseline: eval on a prepared incident"},
    {"DualPrepared/1", "dual-scattering baseline: evalPdf on a prepared incident"},
    {"DualPrepared/2", "dual-scattering baseline: sample on a prepared incident"},
    {"DualConstruct/1", "dual-scattering baseline construction: energy clamp table (default)"},
    {"DualConstruct/0", "dual-scattering baseline construction without the clamp"},
};

// The row of a benchmark's name (the end of kEntries when it has none).
size_t entryOf(const std::string& name) {
    size_t k = 0;
    while (k < std::size(kEntries) && name != kEntries[k].name) ++k;
    return k;
}

const char* describe(const std::string& name) {
    const size_t k = entryOf(name);
    return k < std::size(kEntries) ? kEntries[k].what : "";
}

// The compiled FixedMlp kernels this CPU runs, best first.
std::string kernelNames() {
    std::string names;
    for (const FixedMlpKernel& k : fixedMlpKernels())
        names += (names.empty() ? "" : ", ") + std::string(k.target);
    return names;
}

}  // namespace

BENCHMARK(FiberEval);
BENCHMARK(FiberEvalPrepared);
BENCHMARK(FiberSample);
BENCHMARK(YarnEval)->Arg(1)->Arg(0);
BENCHMARK(YarnPdf);
BENCHMARK(YarnSample)->Arg(1)->Arg(0);
BENCHMARK(YarnPrepared)->ArgsProduct({{0, 1, 2}, {1, 0}});
BENCHMARK(YarnBatch)->Arg(0)->Arg(1)->Arg(2);
BENCHMARK(FiberPrepare);
BENCHMARK(YarnPrepare);
BENCHMARK(FiberVertex);
BENCHMARK(YarnVertex);
BENCHMARK(YarnMNetwork);
BENCHMARK(MNetwork)->Arg(1)->Arg(0);
BENCHMARK(YarnTNetwork);
BENCHMARK(TNetwork)->Arg(1)->Arg(0);
BENCHMARK(MNetworkBatch)->Arg(16)->Arg(256);
BENCHMARK(TNetworkBatch)->Arg(256);
BENCHMARK(YarnRLobe);
BENCHMARK(MlpForwardBatchOfOne);
BENCHMARK(YarnConstruct)->Arg(2)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);
BENCHMARK(DualPrepared)->Arg(0)->Arg(1)->Arg(2);
BENCHMARK(DualConstruct)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

int main(int argc, char** argv) {
    std::string md = "bench/results/bsdf.md";
    std::vector<char*> args;
    for (int k = 0; k < argc; ++k) {
        if (std::strncmp(argv[k], "--md=", 5) == 0)
            md = argv[k] + 5;
        else if (std::strncmp(argv[k], "--model=", 8) == 0)
            gModelPath = argv[k] + 8;
        else
            args.push_back(argv[k]);
    }
    int count = static_cast<int>(args.size());
    benchmark::Initialize(&count, args.data());
    if (benchmark::ReportUnrecognizedArguments(count, args.data())) return 1;
    TableReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    benchmark::Shutdown();

    // Interleaved repetitions report in a random order.
    std::stable_sort(reporter.rows.begin(), reporter.rows.end(), [](const auto& a, const auto& b) {
        return entryOf(a.name) < entryOf(b.name);
    });
    auto fastest = [&](const char* name) {
        for (const auto& row : reporter.rows)
            if (row.name == name) return row.fastest();
        return 0.0;
    };
    const double fiber = fastest("FiberEval");
    std::ostringstream out;
    out << "# Yarn BSDF cost (bench/bsdf)\n\n"
        << "One machine, one thread; CPU time per call over 4096 fixed random (wi, wo) pairs (wi "
           "in the upper hemisphere), fastest of the repetitions (interleaved). Model: `"
        << std::filesystem::path(gModelPath).filename().string() << "` ("
        << model().mNet.widthsText() << " M network, " << model().tNet.widthsText()
        << " T network). Ratios are to FiberBcsdf::eval in the same run. Network kernel: "
        << mNet().target() << " (Highway dynamic dispatch; this CPU runs " << kernelNames()
        << ").\n\n"
        << "| benchmark | what | ns per call | / fiber eval |\n| --- | --- | --- | --- |\n";
    for (const auto& row : reporter.rows) {
        char line[512];
        if (row.name.find("Construct") != std::string::npos)
            std::snprintf(line, sizeof line, "| %s | %s | %.3g ms | |\n", row.name.c_str(),
                          describe(row.name), row.fastest() * 1e-6);
        else
            std::snprintf(line, sizeof line, "| %s | %s | %.0f | %.2f |\n", row.name.c_str(),
                          describe(row.name), row.fastest(),
                          fiber > 0 ? row.fastest() / fiber : 0.0);
        out << line;
    }
    // Issue 17's targets for the per-wo cost, as ratios to FiberBcsdf::eval.
    auto ratio = [&](const char* name) { return fiber > 0 ? fastest(name) / fiber : 0.0; };
    if (ratio("YarnPrepared/0/1") > 0) {
        char line[384];
        std::snprintf(line, sizeof line,
                      "\nPer-wo cost on a prepared incident / FiberBcsdf::eval, tabulated "
                      "sampling: eval %.2f (target <= 1.2), evalPdf %.2f (<= 1.5), sample %.2f "
                      "(<= 2); fitted sampling: %.2f, %.2f, %.2f.\n",
                      ratio("YarnPrepared/0/1"), ratio("YarnPrepared/1/1"),
                      ratio("YarnPrepared/2/1"), ratio("YarnPrepared/0/0"),
                      ratio("YarnPrepared/1/0"), ratio("YarnPrepared/2/0"));
        out << line;
    }
    if (fastest("FiberVertex") > 0 && fastest("YarnVertex") > 0) {
        char line[256];
        std::snprintf(line, sizeof line,
                      "\nOne path vertex (prepare, NEE evalPdf, sample): yarn %.0f ns, fiber %.0f "
                      "ns, yarn / fiber %.2f.\n",
                      fastest("YarnVertex"), fastest("FiberVertex"),
                      fastest("YarnVertex") / fastest("FiberVertex"));
        out << line;
    }
    if (!md.empty()) {
        writeFileAtomic(md, out.str());
        std::printf("wrote %s\n", md.c_str());
    }
    return 0;
}
