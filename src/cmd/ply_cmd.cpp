// weft ply: the procedural ply generator (docs/design.md 4) as centre-line files.
#include <cstdio>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "commands.h"
#include "weft/core/curves.h"
#include "weft/core/error.h"
#include "weft/ply/ply.h"
#include "weft/yarn/material_preset.h"

namespace weft::cmd {

namespace {

struct PlyOptions {
    MaterialOptions material;
    PlyGeometryOptions geometry;
    double radius = 1, length = 0;
    uint64_t seed = 0;
    int pointsPerTwist = 32;
    std::string out;
};

bool endsWith(const std::string& s, const std::string& suffix) {
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

void runPly(const PlyOptions& o) {
    PlyParams params;
    if (!o.material.preset.empty()) {
        if (o.geometry.anyGiven())
            throw InputError("give either --preset NAME or --fibers/--density/--twist, not both");
        params = findMaterialPreset(o.material.preset).ply;
    } else {
        if (!o.geometry.allGiven())
            throw InputError("give --preset NAME, or all of --fibers N --density RHO --twist ALPHA");
        params = o.geometry.params();
    }
    const PlyGeometry ply = generatePly(params, o.radius, o.length, o.seed);
    CurveSet set;
    for (std::vector<Vec3>& line : ply.polylines(o.pointsPerTwist)) {
        Curve& fiber = set.curves.emplace_back();
        fiber.radii.assign(line.size(), ply.fiberRadius);
        fiber.points = std::move(line);
    }
    if (endsWith(o.out, ".bcc")) {
        writeBcc(o.out, set, "weft ply");
    } else {
        writeCurveText(o.out, set);
    }
    const nlohmann::json summary = {
        {"fibers", ply.params.fibers},     {"density", ply.params.density},
        {"twist", ply.params.twist},       {"radius", ply.radius},
        {"length", ply.length},            {"fiber_radius", ply.fiberRadius},
        {"seed", ply.seed},                {"points", set.pointCount()},
        {"twist_period", std::isfinite(ply.twistPeriod()) ? nlohmann::json(ply.twistPeriod())
                                                          : nlohmann::json(nullptr)},
        {"out", o.out}};
    std::printf("%s\n", summary.dump(2).c_str());
}

}  // namespace

void addPlyCommand(CLI::App& app) {
    auto o = std::make_shared<PlyOptions>();
    CLI::App* ply = app.add_subcommand(
        "ply", "Generate the fiber centre lines of a straight ply along +z (x y z radius text "
               "polylines, or .bcc); prints a JSON summary");
    o->material.add(*ply, true);
    // --params has no meaning for geometry; keep the flag set to --preset only.
    ply->remove_option(ply->get_option("--params"));
    o->geometry.add(*ply);
    ply->add_option("--radius", o->radius, "ply radius R > 0")->default_val(1.0);
    ply->add_option("--length", o->length, "ply length L > 0 (axis from z=0 to z=L)")->required();
    addSeedOption(*ply, o->seed, "random seed of the fiber placement");
    ply->add_option("--points-per-twist", o->pointsPerTwist,
                    "polyline points per twist period (>= 16)")
        ->default_val(32)
        ->check(CLI::Range(16, 100000));
    ply->add_option("--out", o->out, "output FILE.txt (text polylines) or FILE.bcc")->required();
    ply->callback([o] { runPly(*o); });
}

}  // namespace weft::cmd
