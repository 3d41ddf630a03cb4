// bench/gather — gather throughput against bare Embree on the same ply.
//
// For each preset: the ply the gather traces (one twist period, periodic),
// (a) bare Embree: random incoherent rays (origin uniform in the ply's
//     bounding cylinder, direction uniform on the sphere, tfar = the
//     cylinder's side), one rtcIntersect1 each, no filter, no shading;
// (b) the gather's own rays per second during its random walks (BCSDF
//     sampling, exclusion filter, periodic wrapping included),
// both with 1 and 2 threads in the same run, and the ratio (b) / (a).
// Writes a Markdown table (default bench/results/gather.md). Optionally times
// a full-size fleece gather (--fleece-paths 16000000: the target).
#include "weft/gather/gather.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <sstream>

#include "weft/core/file.h"
#include "weft/core/math.h"
#include "weft/core/rng.h"
#include "weft/gather/ply_tracer.h"
#include "weft/yarn/material_preset.h"

using namespace weft;

namespace {

double bareEmbreeRaysPerSecond(const PeriodicPlyTracer& tracer, int threads, int64_t rays) {
    std::atomic<int64_t> hits{0};
    tbb::task_arena arena(threads);
    const auto start = std::chrono::steady_clock::now();
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int64_t>(0, rays / 1024), [&](const auto& range) {
            for (int64_t chunk = range.begin(); chunk != range.end(); ++chunk) {
                Rng rng(static_cast<uint64_t>(chunk), 5);
                int64_t local = 0;
                for (int k = 0; k < 1024; ++k) {
                    const double rad = std::sqrt(rng.uniform()), a = kTwoPi * rng.uniform();
                    const Vec3 org{rad * std::cos(a), rad * std::sin(a), tracer.period() * rng.uniform()};
                    const double z = 2 * rng.uniform() - 1, p = kTwoPi * rng.uniform();
                    const double s = std::sqrt(1 - z * z);
                    const Vec3 dir{s * std::cos(p), s * std::sin(p), z};
                    local += tracer.intersectOnce(org, dir, tracer.cylinderExitDistance(org, dir), -1) >= 0;
                }
                hits += local;
            }
        });
    });
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return (rays / 1024 * 1024) / seconds;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"gather throughput vs bare Embree, per preset, 1 and 2 threads"};
    int64_t paths = 200000, bareRays = 2000000, fleecePaths = 0;
    std::string out = "bench/results/gather.md";
    app.add_option("--paths", paths, "paths per gather run")->default_val(paths);
    app.add_option("--bare-rays", bareRays, "rays per bare Embree run")->default_val(bareRays);
    app.add_option("--fleece-paths", fleecePaths,
                   "also time one fleece gather of this many paths on 2 threads (0: skip)")
        ->default_val(0);
    app.add_option("--out", out, "Markdown table")->default_val(out);
    CLI11_PARSE(app, argc, argv);

    std::ostringstream md;
    md << "# Gather throughput (bench/gather)\n\n"
       << "One run, one machine (" << tbb::this_task_arena::max_concurrency()
       << " hardware threads). Bare Embree: random incoherent rays through the same ply "
          "(rtcIntersect1, no filter, no shading). Gather: rays traced during the random walks "
          "(BCSDF sampling, exclusion filter, periodic wrap included) over walk time. "
       << paths << " paths per gather run, default 22x90x45x90 bins.\n\n"
       << "| preset | threads | bare Embree rays/s | gather rays/s | gather / bare | paths/s | mean depth |\n"
       << "| --- | --- | --- | --- | --- | --- | --- |\n";
    for (const auto& preset : materialPresets()) {
        GatherOptions o;
        o.fiber = preset.fiber;
        o.ply = preset.ply;
        o.material = std::string(preset.name);
        o.paths = paths;
        o.seed = 1;
        o.quiet = true;
        const PeriodicPlyTracer tracer(generatePly(preset.ply, 1.0, 1.0, o.seed), o.segmentsPerTwist);
        for (int threads : {1, 2}) {
            o.threads = threads;
            const double bare = bareEmbreeRaysPerSecond(tracer, threads, bareRays);
            const GatherStats s = gatherRdm(o).stats;
            const double rays = s.rays / s.walkSeconds;
            char line[512];
            std::snprintf(line, sizeof line, "| %s | %d | %.3g | %.3g | %.2f | %.3g | %.2f |\n",
                          std::string(preset.name).c_str(), threads, bare, rays, rays / bare,
                          s.paths / s.walkSeconds, s.meanDepth);
            md << line;
            std::fputs(line, stdout);
            std::fflush(stdout);
        }
    }
    {
        // The primitive choice (docs/gather.md): bare Embree rays on the fleece
        // ply with linear round curves (the gather's) and cubic Catmull-Rom
        // round curves through the same helix points.
        const MaterialPreset& fleece = findMaterialPreset("fleece");
        const PlyGeometry ply = generatePly(fleece.ply, 1.0, 1.0, 1);
        md << "\nPrimitive choice, fleece ply, bare Embree rays/s on 1 thread:\n\n"
           << "| primitive | segments per twist | rays/s | vs linear 128 |\n| --- | --- | --- | --- |\n";
        double linear = 0;
        const std::pair<FiberPrimitive, int> variants[] = {{FiberPrimitive::RoundLinear, 128},
                                                           {FiberPrimitive::RoundLinear, 256},
                                                           {FiberPrimitive::RoundCatmullRom, 32},
                                                           {FiberPrimitive::RoundCatmullRom, 64}};
        for (const auto& [primitive, segments] : variants) {
            // Best of three runs after a warm-up: single runs vary by ~10%.
            const PeriodicPlyTracer tracer(ply, segments, primitive);
            bareEmbreeRaysPerSecond(tracer, 1, bareRays / 4);
            double rate = 0;
            for (int run = 0; run < 3; ++run)
                rate = std::max(rate, bareEmbreeRaysPerSecond(tracer, 1, bareRays));
            if (linear == 0) linear = rate;
            char line[256];
            std::snprintf(line, sizeof line, "| %s | %d | %.3g | %.2f |\n",
                          primitive == FiberPrimitive::RoundLinear ? "round linear" : "round Catmull-Rom",
                          segments, rate, rate / linear);
            md << line;
            std::fputs(line, stdout);
        }
    }
    if (fleecePaths > 0) {
        GatherOptions o;
        o.fiber = findMaterialPreset("fleece").fiber;
        o.ply = findMaterialPreset("fleece").ply;
        o.paths = fleecePaths;
        o.seed = 1;
        o.threads = 2;
        o.quiet = true;
        const GatherStats s = gatherRdm(o).stats;
        char line[512];
        std::snprintf(line, sizeof line,
                      "\nFull fleece gather: %lld paths on 2 threads in %.1f s (walks %.1f s): "
                      "%.3g paths/s, %.3g rays/s, mean depth %.2f, truncated %.2g.\n",
                      static_cast<long long>(s.paths), s.seconds, s.walkSeconds,
                      s.paths / s.walkSeconds, s.rays / s.walkSeconds, s.meanDepth,
                      static_cast<double>(s.truncatedPaths) / s.paths);
        md << line;
        std::fputs(line, stdout);
    }
    writeFileAtomic(out, md.str());
    std::printf("wrote %s\n", out.c_str());
    return 0;
}
