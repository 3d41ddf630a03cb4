// bench/curves — the time of `weft curves info` (render/curve_report.h) on
// files of 10^5 points.
//
// Two generated BCC files, each read back with readCurves (core/curves.h,
// the reader of `weft render` and `weft curves info`) and
// reported without a radius (counts and the closest contact) and with one
// (plus the overlap at that radius):
//   random walks: 100 smooth random walks of 1000 points each (step 0.5,
//                 the direction turned a little per step, kept inside a
//                 60-unit box), yarn radius 0.25;
//   tiled knit:   the shared stockinette knit (data/curves, 826 points)
//                 tiled 11 x 11 side by side (99946 points), at its radius 1
//                 (skipped when the file is missing; --knit names it).
// Times are the median of three runs on one thread. Writes a Markdown table
// (default bench/results/curves.md).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "weft/core/curves.h"
#include "weft/core/file.h"
#include "weft/core/rng.h"
#include "weft/render/curve_report.h"

using namespace weft;

namespace {

double medianSeconds(const std::function<void()>& f) {
    std::vector<double> times;
    for (int run = 0; run < 3; ++run) {
        const auto start = std::chrono::steady_clock::now();
        f();
        times.push_back(
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    std::sort(times.begin(), times.end());
    return times[1];
}

CurveSet randomWalks(int curves, int points, uint64_t seed) {
    const double box = 60, step = 0.5;
    CurveSet set;
    Rng rng(0, seed);
    for (int c = 0; c < curves; ++c) {
        Vec3 p{box * rng.uniform(), box * rng.uniform(), box * rng.uniform()};
        Vec3 dir = normalize(Vec3{rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5});
        std::vector<Vec3> curve;
        for (int k = 0; k < points; ++k) {
            curve.push_back(p);
            dir = normalize(
                dir + 0.3 * Vec3{rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5});
            // Turn back at the walls of the box.
            if (p.x + step * dir.x < 0 || p.x + step * dir.x > box) dir.x = -dir.x;
            if (p.y + step * dir.y < 0 || p.y + step * dir.y > box) dir.y = -dir.y;
            if (p.z + step * dir.z < 0 || p.z + step * dir.z > box) dir.z = -dir.z;
            p += step * dir;
        }
        set.curves.push_back({curve, {}, false, CurveBasis::Polyline, {}});
    }
    return set;
}

CurveSet tiledKnit(const std::string& knitPath, int tiles) {
    const CurveSet knit = readCurves(knitPath);
    const Bounds3 box = bounds(knit);
    const Vec3 size = box.hi - box.lo;
    CurveSet set;
    for (int i = 0; i < tiles; ++i)
        for (int j = 0; j < tiles; ++j)
            for (const Curve& curve : knit.curves) {
                Curve moved = curve;
                for (Vec3& p : moved.points) p += Vec3{i * size.x, j * size.y, 0};
                set.curves.push_back(moved);
            }
    return set;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"time of the curve report (weft curves info) on files of 10^5 points"};
    std::string out = "bench/results/curves.md";
    std::string knit = "data/curves/knit-stockinette-tiny.bcc";  // from the repository root
    app.add_option("--out", out, "Markdown table")->default_val(out);
    app.add_option("--knit", knit, "the shared knit BCC")->default_val(knit);
    CLI11_PARSE(app, argc, argv);

    const std::string dir =
        (std::filesystem::temp_directory_path() / ("bench-curves-" + std::to_string(getpid())))
            .string();
    std::filesystem::create_directories(dir);
    struct Case {
        std::string name, file;
        double radius;
    };
    std::vector<Case> cases;
    writeBcc(dir + "/walks.bcc", randomWalks(100, 1000, 1), "bench/curves");
    cases.push_back({"random walks, 100 x 1000 points", dir + "/walks.bcc", 0.25});
    if (std::filesystem::exists(knit)) {
        writeBcc(dir + "/knit.bcc", tiledKnit(knit, 11), "bench/curves");
        cases.push_back({"shared knit tiled 11 x 11", dir + "/knit.bcc", 1.0});
    }

    std::ostringstream md;
    md << "# Curve report (bench/curves)\n\n"
       << "The time of `weft curves info` on files of 10^5 points: read (the renderer's BCC "
          "reader), the report without a radius (counts, lengths, the closest contact), and "
          "with one (plus the overlap at that radius). Median of three runs, one thread, one "
          "machine.\n\n"
       << "| file | points | segments | read s | report s | report with radius s | min distance "
          "| radius | overlap fraction |\n"
       << "| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
    for (const Case& c : cases) {
        CurveSet set;
        const double read = medianSeconds([&] { set = readCurves(c.file); });
        render::CurveReport plain, withRadius;
        const double report = medianSeconds([&] { plain = render::curveReport(set); });
        const double overlap =
            medianSeconds([&] { withRadius = render::curveReport(set, c.radius); });
        char line[512];
        std::snprintf(line, sizeof line,
                      "| %s | %zu | %zu | %.3f | %.3f | %.3f | %.4g | %g | %.3f |\n",
                      c.name.c_str(), plain.points, plain.segments, read, report, overlap,
                      plain.minDistance(), c.radius, withRadius.overlap->fraction);
        md << line;
        std::fputs(line, stdout);
        std::fflush(stdout);
    }
    std::filesystem::remove_all(dir);
    writeFileAtomic(out, md.str());
    std::printf("wrote %s\n", out.c_str());
    return 0;
}
