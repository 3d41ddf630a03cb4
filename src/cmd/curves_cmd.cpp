// weft curves info: what a yarn curve file holds and the radius it allows
// (render/curve_report.h, docs/curves.md); weft curves points: its control
// points as .npy, for per-point colours.
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "commands.h"
#include "weft/core/curves.h"
#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/npy.h"
#include "weft/render/curve_report.h"

namespace weft::cmd {

namespace {

struct CurvesInfoOptions {
    std::string file, json;
    double radius = 0;
    CLI::Option* radiusOpt = nullptr;
};

std::string number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

std::string point(const Vec3& p) {
    return "(" + number(p.x) + ", " + number(p.y) + ", " + number(p.z) + ")";
}

// One "label  value" line, the values aligned in one column.
void printLine(const std::string& label, const std::string& value) {
    std::printf("%-16s %s\n", label.c_str(), value.c_str());
}

// The report as a person reads it: one aligned line per quantity.
void printReport(const std::string& file, const CurveSet& set, const render::CurveReport& r) {
    printLine("file", file);
    printLine(
        "curves",
        std::to_string(r.curves) + " (" + std::to_string(r.closedCurves) + " closed), " +
            (r.basis == CurveBasis::CatmullRom ? "Catmull-Rom (analysed on the control polygon)"
                                               : "polyline"));
    printLine("points", std::to_string(r.points));
    printLine("segments", std::to_string(r.segments) + " (" + std::to_string(r.degenerateSegments) +
                              " of zero length)");
    printLine("segment length", "min " + number(r.segmentLengthMin) + ", mean " +
                                    number(r.segmentLengthMean) + ", max " +
                                    number(r.segmentLengthMax));
    printLine("total length", number(r.totalLength));
    printLine("bounds", point(r.bounds.lo) + " to " + point(r.bounds.hi));
    if (r.closest) {
        const std::string where =
            r.closest->curveA == r.closest->curveB
                ? "curve " + std::to_string(r.closest->curveA) + " with itself"
                : "curves " + std::to_string(r.closest->curveA) + " and " +
                      std::to_string(r.closest->curveB);
        printLine("min distance", number(r.closest->distance) + " (" + where + ", at " +
                                      point(r.closest->pointA) + " and " +
                                      point(r.closest->pointB) + ")");
        printLine("largest radius", number(r.largestRadiusWithoutOverlap()) +
                                        " (the yarns overlap nowhere up to this radius)");
        if (!(r.largestRadiusWithoutOverlap() > 1e-9 * length(r.bounds.hi - r.bounds.lo)))
            printLine("why", render::zeroRadiusExplanation(set, r));
    } else {
        printLine("min distance", "none (no two yarns, and no parts of one, come close)");
        printLine("largest radius", "unbounded");
    }
    if (r.overlap) {
        char fraction[32], depth[32];
        std::snprintf(fraction, sizeof fraction, "%.1f%%", 100 * r.overlap->fraction);
        std::snprintf(depth, sizeof depth, "%.0f%%", 100 * r.overlap->maxDepth);
        const std::string at = "at radius " + number(r.overlap->radius) + ": ";
        printLine("overlap", r.overlap->fraction > 0
                                 ? at + fraction + " of the length, up to " + depth +
                                       " of the diameter, on " +
                                       std::to_string(r.overlap->curvesOverlapping) + " of " +
                                       std::to_string(r.curves) + " curves"
                                 : at + "none");
        if (r.overlap->radius < render::kThinYarnFraction * r.largestRadiusWithoutOverlap())
            printLine("note",
                      "radius " + number(r.overlap->radius) + " is " +
                          number(100 * r.overlap->radius / r.largestRadiusWithoutOverlap()) +
                          "% of the largest radius without overlap: the yarns cover little "
                          "of the space between the curves (units? docs/curves.md)");
    }
}

void runInfo(const CurvesInfoOptions& o) {
    if (o.radiusOpt->count()) render::checkOverlapRadius(o.radius, "--radius");
    checkOutputsSpareInputs({{"FILE", o.file}}, {{"--json", o.json}});
    const CurveSet set = readCurves(o.file);
    const render::CurveReport report =
        render::curveReport(set, o.radiusOpt->count() ? std::optional(o.radius) : std::nullopt,
                            o.file);
    if (!o.json.empty()) {
        nlohmann::json j = render::toJson(report);
        j["file"] = o.file;
        writeFileAtomic(o.json, j.dump(2) + "\n");
    }
    printReport(o.file, set, report);
}

struct CurvesPointsOptions {
    std::string file, out;
};

// The control points as an (n, 4) float64 array: curve index, x, y, z, in
// the file's order and units: what a per-point colour file must follow.
void runPoints(const CurvesPointsOptions& o) {
    if (lowercaseExtension(o.out) != ".npy")
        throw InputError("--out " + o.out + ": expected a path ending in .npy");
    checkOutputsSpareInputs({{"FILE", o.file}}, {{"--out", o.out}});
    const CurveSet set = readCurves(o.file);
    const std::vector<double> rows = pointRows(set);
    writeNpy(o.out, rows.data(), {set.pointCount(), 4});
    std::printf("%s\n", nlohmann::json({{"file", o.file},
                                        {"out", o.out},
                                        {"curves", set.curves.size()},
                                        {"points", set.pointCount()},
                                        {"columns", {"curve", "x", "y", "z"}}})
                            .dump()
                            .c_str());
}

}  // namespace

void addCurvesCommands(CLI::App& app) {
    CLI::App* curves =
        app.add_subcommand("curves", "Inspect yarn curve files (.bcc, .txt, .obj; docs/curves.md)");
    curves->require_subcommand(1);

    auto o = std::make_shared<CurvesInfoOptions>();
    CLI::App* info = curves->add_subcommand(
        "info",
        "Counts, lengths and box of a curve file, the closest approach of two yarns (or of two "
        "parts of one yarn), the largest radius at which no yarns overlap and, with --radius, "
        "how much of the yarn length overlaps at that radius");
    info->add_option("file", o->file, "Curve file (.bcc, .txt or .obj)")->required();
    o->radiusOpt =
        info->add_option("--radius", o->radius,
                         "Yarn radius in the file's units (finite, > 0): report the overlap at it");
    info->add_option("--json", o->json, "Also write the report as JSON (atomically)");
    info->callback([o] { runInfo(*o); });

    auto po = std::make_shared<CurvesPointsOptions>();
    CLI::App* points = curves->add_subcommand(
        "points",
        "The control points of a curve file as an (n, 4) float64 .npy: curve index, x, y, z, in "
        "the file's order and units; a vertex colour file (.npy (n, 3) or .txt) follows the "
        "same order (docs/scene-format.md)");
    points->add_option("file", po->file, "Curve file (.bcc, .txt or .obj)")->required();
    points->add_option("--out", po->out, "Output POINTS.npy (written atomically)")->required();
    points->callback([po] { runPoints(*po); });
}

}  // namespace weft::cmd
