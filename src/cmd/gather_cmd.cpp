// weft gather: the RDM of a ply by random walks through its explicit fibers.
#include <cstdio>
#include <memory>
#include <string>

#include "commands.h"
#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/gather/gather.h"
#include "weft/gather/rdm_image.h"
#include "weft/yarn/material_preset.h"

namespace weft::cmd {

namespace {

struct GatherCliOptions {
    MaterialOptions material;
    PlyGeometryOptions geometry;
    int64_t paths = 0;
    uint64_t seed = 0, plySeed = 0;
    CLI::Option* plySeedOpt = nullptr;
    std::string bins = "22,90,45,90", out;
    int maxDepth = 1000, threads = 0, segmentsPerTwist = 128;
    bool quiet = false;
};

void runGather(const GatherCliOptions& c) {
    GatherOptions o;
    if (!c.material.preset.empty()) {
        if (!c.material.paramsFile.empty() || c.geometry.anyGiven())
            throw InputError("--preset gives fiber and ply parameters: do not combine it with "
                             "--params, --fibers, --density or --twist");
        const MaterialPreset& preset = findMaterialPreset(c.material.preset);
        o.fiber = preset.fiber;
        o.ply = preset.ply;
        o.material = c.material.preset;
    } else {
        if (c.material.paramsFile.empty() || !c.geometry.allGiven())
            throw InputError("give --preset NAME, or --params FILE.json with --fibers N "
                             "--density RHO --twist ALPHA");
        o.fiber = FiberParams::fromJsonFile(c.material.paramsFile);
        o.ply = c.geometry.params();
        o.material = c.material.paramsFile;
    }
    o.paths = c.paths;
    o.seed = c.seed;
    if (c.plySeedOpt->count()) o.plySeed = c.plySeed;
    o.bins = RdmBins::parse(c.bins);
    o.maxDepth = c.maxDepth;
    o.threads = c.threads;
    o.segmentsPerTwist = c.segmentsPerTwist;
    o.quiet = c.quiet;
    o.validate();
    checkOutputsSpareInputs({{"--params", c.material.paramsFile}}, {}, {}, {{"--out", c.out}});
    // Before the (long) gather: a bad destination fails now, not after it.
    TempDirCommit out(c.out);
    const GatherResult result = gatherRdm(o);
    writeGather(result, o, out);
    const GatherStats& s = result.stats;
    std::printf(
        "{\"out\": \"%s\", \"paths\": %lld, \"seconds\": %.3f, \"paths_per_second\": %.0f, "
        "\"rays_per_second\": %.0f, \"mean_depth\": %.3f, \"truncated_fraction\": %.3g}\n",
        c.out.c_str(), static_cast<long long>(s.paths), s.seconds, s.paths / s.seconds,
        s.rays / s.walkSeconds, s.meanDepth, static_cast<double>(s.truncatedPaths) / s.paths);
}

}  // namespace

void addGatherCommand(CLI::App& app) {
    auto o = std::make_shared<GatherCliOptions>();
    CLI::App* gather = app.add_subcommand(
        "gather", "Trace random walks through an explicit ply and write its reflectance "
                  "distribution (RDM: P(T | wi), R and M maps) as NumPy arrays");
    o->material.add(*gather, true);
    o->geometry.add(*gather);
    gather->add_option("--paths", o->paths, "number of random walks, in [1, 2^31]")->required();
    addSeedOption(*gather, o->seed, "random seed of the walks (and of the fiber placement)");
    o->plySeedOpt = addSeedOption(*gather, o->plySeed,
                                  "random seed of the fiber placement only (default: --seed); "
                                  "fix it to compare walks on one ply",
                                  "--ply-seed");
    gather->add_option("--bins", o->bins, "RDM resolution TI,PI,TO,PO (theta_i, phi_i, theta_o, phi_o)")
        ->default_val("22,90,45,90");
    gather->add_option("--max-depth", o->maxDepth, "fiber interactions per path before truncation")
        ->default_val(1000);
    gather->add_option("--threads", o->threads, "worker threads (0: all cores)")->default_val(0);
    gather->add_option("--segments-per-twist", o->segmentsPerTwist,
                       "polyline segments per twist period of the traced fibers (>= 16)")
        ->default_val(128);
    gather->add_flag("--quiet", o->quiet, "no progress output");
    gather->add_option("--out", o->out, "output directory (written atomically)")->required();
    gather->callback([o] { runGather(*o); });

    struct SliceOptions {
        std::string rdm, component = "m", out;
        double thetaI = 45, phiI = 0;
    };
    auto so = std::make_shared<SliceOptions>();
    CLI::App* rdm = app.add_subcommand("rdm", "Inspect a gathered RDM directory");
    rdm->require_subcommand(1);
    CLI::App* slice = rdm->add_subcommand(
        "slice", "PNG of the R or M map of one incident bin over all outgoing directions "
                 "(x: phi_o -180..180, y: theta_o 0 (top) .. 180 degrees)");
    slice->add_option("--rdm", so->rdm, "directory written by weft gather")->required();
    slice->add_option("--component", so->component, "r or m")->default_val("m");
    slice->add_option("--theta-i", so->thetaI, "incident theta in degrees [0, 90]")->default_val(45);
    slice->add_option("--phi-i", so->phiI, "incident phi in degrees [-180, 180]")->default_val(0);
    slice->add_option("--out", so->out, "output PNG")->required();
    slice->callback([so] {
        checkOutputsSpareInputs({}, {{"--out", so->out}}, {{"--rdm", so->rdm}});
        const size_t bin = writeRdmSlicePng(so->rdm, so->component, so->thetaI, so->phiI, so->out);
        std::printf("{\"incident_bin\": %zu, \"out\": \"%s\"}\n", bin, so->out.c_str());
    });
}

}  // namespace weft::cmd
