// bench/bsdf — cost of one yarn BSDF query against the fiber BCSDF (Google Benchmark).
//
// ns per call, one thread, on 4096 fixed random direction pairs (wi in the
// upper hemisphere, wo on the sphere) cycled through so that branches and
// caches see a renderer-like mix: YarnBsdf eval / pdf / sample (with and
// without the energy guard), its parts (the T and M networks through
// FixedMlp, the R lobe), Mlp<float>::forward on a batch of one (what the
// fixed-size evaluator replaces), FiberBcsdf eval / sample, and the time to
// construct a YarnBsdf (model validation, energy guard table).
// Writes a Markdown table (default bench/results/bsdf.md; --md=PATH) with
// every time relative to FiberBcsdf::eval; --benchmark_out=FILE.json adds
// Google Benchmark's JSON. The model: tests/data/fleece-small.json next to
// this file, or --model=PATH. On a shared machine use repetitions:
//     build/release/bench_bsdf --benchmark_repetitions=5 --benchmark_min_time=0.5
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "weft/core/file.h"
#include "weft/core/math.h"
#include "weft/core/rng.h"
#include "weft/fiber/fiber_bcsdf.h"
#include "weft/fit/mlp.h"
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

void YarnMNetwork(benchmark::State& state) {
    const YarnBsdf& bsdf = rawBsdf();
    loop(state, [&](const Vec3& wi, const Vec3& wo, const BsdfSampleInput&) {
        benchmark::DoNotOptimize(bsdf.evalM(wi, wo));
    });
}

void YarnTNetwork(benchmark::State& state) {
    const YarnBsdf& bsdf = rawBsdf();
    loop(state, [&](const Vec3& wi, const Vec3&, const BsdfSampleInput&) {
        benchmark::DoNotOptimize(bsdf.transmission(wi));
    });
}

void YarnRLobe(benchmark::State& state) {
    const RLobe& lobe = rawBsdf().rLobe();
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

void YarnConstruct(benchmark::State& state) {
    const YarnBsdfOptions options{state.range(0) != 0};
    for (auto _ : state) benchmark::DoNotOptimize(YarnBsdf(model(), gModelPath, options));
}

// Console output as usual, and every run's CPU time for the Markdown table
// (with --benchmark_repetitions=K, the median of the K runs).
class TableReporter : public benchmark::ConsoleReporter {
  public:
    struct Row {
        std::string name;
        std::vector<double> nanoseconds;
        double median() const {
            std::vector<double> v = nanoseconds;
            std::sort(v.begin(), v.end());
            return v.empty() ? 0.0 : v[v.size() / 2];
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
            it->nanoseconds.push_back(run.GetAdjustedCPUTime() * toNs);
        }
        ConsoleReporter::ReportRuns(runs);
    }
};

const char* describe(const std::string& name) {
    struct Entry {
        const char* name;
        const char* what;
    };
    static const Entry entries[] = {
        {"FiberEval", "FiberBcsdf::eval (the reference)"},
        {"FiberSample", "FiberBcsdf::sample"},
        {"YarnEval/1", "YarnBsdf::eval: T network, R lobe, M network, energy guard"},
        {"YarnEval/0", "YarnBsdf::eval without the energy guard"},
        {"YarnPdf", "YarnBsdf::pdf: T network, eq. 10 lobes"},
        {"YarnSample/1", "YarnBsdf::sample: lobe choice, direction, eval and pdf, energy guard"},
        {"YarnSample/0", "YarnBsdf::sample without the energy guard"},
        {"YarnMNetwork", "M network alone (FixedMlp, 6-21-21-21-3)"},
        {"YarnTNetwork", "T network alone (FixedMlp, 3-7-7-1)"},
        {"YarnRLobe", "R lobe alone (eq. 8 with masking)"},
        {"MlpForwardBatchOfOne", "M network through Mlp<float>::forward, batch of 1"},
        {"YarnConstruct/1", "YarnBsdf construction with the energy guard table"},
        {"YarnConstruct/0", "YarnBsdf construction without the guard"},
    };
    for (const Entry& e : entries)
        if (name.rfind(e.name, 0) == 0) return e.what;
    return "";
}

}  // namespace

BENCHMARK(FiberEval);
BENCHMARK(FiberSample);
BENCHMARK(YarnEval)->Arg(1)->Arg(0);
BENCHMARK(YarnPdf);
BENCHMARK(YarnSample)->Arg(1)->Arg(0);
BENCHMARK(YarnMNetwork);
BENCHMARK(YarnTNetwork);
BENCHMARK(YarnRLobe);
BENCHMARK(MlpForwardBatchOfOne);
BENCHMARK(YarnConstruct)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

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

    double fiber = 0;
    for (const auto& row : reporter.rows)
        if (row.name == "FiberEval") fiber = row.median();
    std::ostringstream out;
    out << "# Yarn BSDF cost (bench/bsdf)\n\n"
        << "One machine, one thread; CPU time per call over 4096 fixed random (wi, wo) pairs (wi "
           "in the upper hemisphere), median of the repetitions. Model: `"
        << std::filesystem::path(gModelPath).filename().string()
        << "` (6-21-21-21-3 M network). Ratios are to FiberBcsdf::eval in the same run.\n\n"
        << "| benchmark | what | ns per call | / fiber eval |\n| --- | --- | --- | --- |\n";
    for (const auto& row : reporter.rows) {
        char line[512];
        if (row.name.rfind("YarnConstruct", 0) == 0)
            std::snprintf(line, sizeof line, "| %s | %s | %.3g ms | |\n", row.name.c_str(),
                          describe(row.name), row.median() * 1e-6);
        else
            std::snprintf(line, sizeof line, "| %s | %s | %.0f | %.2f |\n", row.name.c_str(),
                          describe(row.name), row.median(), fiber > 0 ? row.median() / fiber : 0.0);
        out << line;
    }
    if (!md.empty()) {
        writeFileAtomic(md, out.str());
        std::printf("wrote %s\n", md.c_str());
    }
    return 0;
}
