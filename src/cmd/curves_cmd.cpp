// weft curves info: what a yarn curve file holds and the radius it allows
// (render/curve_report.h, docs/curves.md).
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
void printReport(const std::string& file, const render::CurveReport& r) {
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
    printReport(o.file, report);
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
}

}  // namespace weft::cmd
