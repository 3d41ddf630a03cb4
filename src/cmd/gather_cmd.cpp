// weft gather: the RDM of a ply by random walks through its explicit fibers.
#include <cstdio>
#include <memory>
#include <string>

#include "commands.h"
#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/text_parse.h"
#include "weft/gather/colour_paths.h"
#include "weft/gather/family.h"
#include "weft/gather/gather.h"
#include "weft/gather/gather_merge.h"
#include "weft/gather/rdm_image.h"
#include "weft/yarn/material_preset.h"

namespace weft::cmd {

namespace {

// The options of the walks that weft gather and weft gather family share.
struct WalkCliOptions {
    std::string bins, shard;
    int maxDepth = 1000, threads = 0, segmentsPerTwist = 128;
    bool quiet = false;
    CLI::Option* shardOpt = nullptr;

    void add(CLI::App& cmd, const std::string& defaultBins, const std::string& binsHelp,
             const std::string& shardHelp) {
        bins = defaultBins;
        cmd.add_option("--bins", bins, binsHelp)->default_val(defaultBins);
        cmd.add_option("--max-depth", maxDepth, "fiber interactions per path before truncation")
            ->default_val(1000);
        cmd.add_option("--threads", threads, "worker threads (0: all cores)")->default_val(0);
        cmd.add_option("--segments-per-twist", segmentsPerTwist,
                       "polyline segments per twist period of the traced fibers (>= 16)")
            ->default_val(128);
        shardOpt = cmd.add_option("--shard", shard, shardHelp);
        cmd.add_flag("--quiet", quiet, "no progress output");
    }
    // Into GatherOptions or FamilyGatherOptions (the same fields).
    template <typename Options>
    void applyTo(Options& o) const {
        o.bins = RdmBins::parse(bins);
        o.maxDepth = maxDepth;
        o.threads = threads;
        o.segmentsPerTwist = segmentsPerTwist;
        o.quiet = quiet;
        if (shardOpt->count()) o.shard = Shard::parse(shard, "--shard");
    }
};

struct GatherCliOptions {
    MaterialOptions material;
    PlyGeometryOptions geometry;
    WalkCliOptions walks;
    int64_t paths = 0;
    uint64_t seed = 0, plySeed = 0;
    CLI::Option* plySeedOpt = nullptr;
    std::string out;
    CLI::Option* pathsOpt = nullptr;
    bool anyColour = false;
};

// The one-line JSON summary of a gather or a merge.
void printGatherSummary(const std::string& out, const GatherResult& r) {
    const GatherStats& s = r.stats;
    nlohmann::json line = {{"out", out},
                           {"paths", s.paths},
                           {"seconds", s.seconds},
                           {"paths_per_second", std::round(s.paths / s.seconds)},
                           {"rays_per_second", std::round(s.rays / s.walkSeconds)},
                           {"mean_depth", s.meanDepth},
                           {"truncated_fraction", static_cast<double>(s.truncatedPaths) / s.paths},
                           {"shards", s.shards}};
    // How far M light travels in the ply (gather.h; none after a recolouring).
    if (!r.exitDistance.empty())
        for (int c = 0; c < 3; ++c)
            line["m_exit_distance_median"].push_back(summarizeExitDistance(r.exitDistance, c).median);
    std::printf("%s\n", line.dump().c_str());
}

void runGather(const GatherCliOptions& c) {
    // Not CLI11-required: `weft gather merge` does without them.
    if (!c.pathsOpt->count() || c.out.empty())
        throw InputError("weft gather needs --paths N and --out DIR (or: weft gather merge "
                         "PART... --out DIR)");
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
    c.walks.applyTo(o);
    o.anyColour = c.anyColour;
    o.validate();
    checkOutputsSpareInputs({{"--params", c.material.paramsFile}}, {}, {}, {{"--out", c.out}});
    // Before the (long) gather: a bad destination fails now, not after it.
    TempDirCommit out(c.out);
    if (c.walks.shardOpt->count()) {
        // A part for `weft gather merge` (gather_merge.h), even for 0/1.
        const GatherSums sums = gatherSums(o);
        writeGatherPart(sums, o, out);
        std::printf(
            "{\"out\": \"%s\", \"shard\": \"%s\", \"first_path\": %lld, \"end_path\": %lld, "
            "\"seconds\": %.3f, \"paths_per_second\": %.0f}\n",
            c.out.c_str(), o.shard.toString().c_str(), static_cast<long long>(sums.firstPath),
            static_cast<long long>(sums.endPath), sums.seconds,
            (sums.endPath - sums.firstPath) / sums.seconds);
        return;
    }
    const GatherResult result = gatherRdm(o);
    writeGather(result, o, out);
    printGatherSummary(c.out, result);
}

struct MergeCliOptions {
    std::vector<std::string> parts;
    std::string out;
};

void runGatherMerge(const MergeCliOptions& c) {
    std::vector<CommandPath> inputs;
    for (const std::string& part : c.parts) inputs.push_back({"part", part});
    checkOutputsSpareInputs({}, {}, inputs, {{"--out", c.out}});
    TempDirCommit out(c.out);
    MergedGather merged = mergeGatherParts(c.parts);
    const GatherResult result =
        normaliseGather(std::move(merged.sums), merged.options, merged.shards);
    writeGather(result, merged.options, out);
    printGatherSummary(c.out, result);
}

struct RecolourCliOptions {
    std::string gather, cTT, out;
};

void runGatherRecolour(const RecolourCliOptions& c) {
    const Rgb cTT = parseColour(c.cTT, "--c-tt");
    checkOutputsSpareInputs({}, {}, {{"gather", c.gather}}, {{"--out", c.out}});
    TempDirCommit out(c.out);
    RecolouredGather recoloured = recolourGather(c.gather, cTT);
    const Rgb& gathered = recoloured.gatheredCTT;
    const GatherResult result = normaliseGather(std::move(recoloured.sums), recoloured.options);
    writeGather(result, recoloured.options, out,
                {{"recoloured_from",
                  {{"gather", c.gather}, {"c_tt", {gathered.r, gathered.g, gathered.b}}}}});
    printGatherSummary(c.out, result);
}

struct FamilyCliOptions {
    WalkCliOptions walks;
    std::string box, out, design = "halton";
    int points = 0;
    int64_t paths = 0;
    uint64_t seed = 0;
};

void runGatherFamily(const FamilyCliOptions& c) {
    FamilyGatherOptions o;
    if (!c.box.empty()) o.box = FamilyBox::fromJsonFile(c.box);
    o.points = c.points;
    o.pathsPerPoint = c.paths;
    o.seed = c.seed;
    o.design = parseFamilyDesign(c.design, "--design");
    c.walks.applyTo(o);
    o.validate();
    checkOutputsSpareInputs({{"--box", c.box}}, {}, {}, {});
    const FamilyGatherSummary s = gatherFamily(o, c.out);
    const nlohmann::json line = familyGatherSummaryJson(o, s, c.out);
    std::printf("%s\n", line.dump().c_str());
}

}  // namespace

void addGatherCommand(CLI::App& app) {
    auto o = std::make_shared<GatherCliOptions>();
    CLI::App* gather = app.add_subcommand(
        "gather", "Trace random walks through an explicit ply and write its reflectance "
                  "distribution (RDM: P(T | wi), R and M maps) as NumPy arrays");
    o->material.add(*gather, true);
    o->geometry.add(*gather);
    o->pathsOpt = gather->add_option("--paths", o->paths,
                                     "number of random walks, in [1, 2^31] (required; with "
                                     "--shard: of the whole gather)");
    addSeedOption(*gather, o->seed, "random seed of the walks (and of the fiber placement)");
    o->plySeedOpt = addSeedOption(*gather, o->plySeed,
                                  "random seed of the fiber placement only (default: --seed); "
                                  "fix it to compare walks on one ply",
                                  "--ply-seed");
    o->walks.add(*gather, "22,90,45,90",
                 "RDM resolution TI,PI,TO,PO (theta_i, phi_i, theta_o, phi_o)",
                 "K/N: walk only shard K (0..N-1) of N, paths [K P/N, (K+1) P/N), and write a "
                 "part for weft gather merge (docs/cluster.md)");
    gather->add_flag("--any-colour", o->anyColour,
                     "choose fiber lobes independently of C_TT and record every path (25 bytes "
                     "each), so that weft gather recolour gives the RDM of any C_TT "
                     "(docs/gather.md)");
    gather->add_option("--out", o->out, "output directory (written atomically; required)");

    auto mo = std::make_shared<MergeCliOptions>();
    CLI::App* merge = gather->add_subcommand(
        "merge", "Add the parts written by weft gather --shard K/N into one gather directory, "
                 "bit for bit the unsharded gather's (docs/cluster.md)");
    merge->add_option("parts", mo->parts, "the N part directories, shards 0/N .. N-1/N in any order")
        ->required();
    merge->add_option("--out", mo->out, "output gather directory (written atomically)")->required();
    merge->callback([mo] { runGatherMerge(*mo); });

    auto ro = std::make_shared<RecolourCliOptions>();
    CLI::App* recolour = gather->add_subcommand(
        "recolour", "Write the gather of another fiber colour C_TT from a gather made with "
                    "--any-colour, without walking again (docs/gather.md)");
    recolour->add_option("gather", ro->gather, "gather directory written with --any-colour")
        ->required();
    recolour->add_option("--c-tt", ro->cTT, "the new C_TT as R,G,B, each in [0, 1]")->required();
    recolour->add_option("--out", ro->out, "output gather directory (written atomically)")
        ->required();
    recolour->callback([ro] { runGatherRecolour(*ro); });
    auto fo = std::make_shared<FamilyCliOptions>();
    CLI::App* family = gather->add_subcommand(
        "family",
        "Gather the yarns of a family: --points plies spread over a box of yarn "
        "parameters (fiber count, density, twist, the fiber's lobe widths and C_R), "
        "each an any-colour gather of --paths walks in DIR/points/NNNNN "
        "(docs/family.md)");
    family->add_option("--box", fo->box,
                       "BOX.json: {\"fibers\": [lo, hi], \"density\": [lo, hi], \"twist\": ..., "
                       "\"beta_r_deg\", \"beta_tt_deg\", \"gamma_tt_deg\", \"c_r\"} (default: "
                       "the box of docs/family.md, which holds the five presets)");
    family->add_option("--points", fo->points, "yarns of the box, in [1, 65536]")->required();
    family->add_option("--paths", fo->paths, "random walks per yarn, in [1, 2^31]")->required();
    addSeedOption(*family, fo->seed, "random seed of the points and of every yarn's walks");
    family
        ->add_option("--design", fo->design,
                     "how the yarns spread over the box: halton (uniform) or edges (denser "
                     "towards the box's faces, where the five presets sit; docs/family.md)")
        ->default_val("halton");
    fo->walks.add(*family, "11,45,15,30", "each yarn's RDM resolution TI,PI,TO,PO",
                  "K/N: gather only shard K (0..N-1) of N of the points, into the same --out as "
                  "the other shards (docs/cluster.md)");
    family
        ->add_option("--out", fo->out,
                     "family directory (created; points already gathered there are kept)")
        ->required();
    family->callback([fo] { runGatherFamily(*fo); });
    gather->require_subcommand(0, 1);
    gather->callback([o, merge, recolour, family] {
        if (!merge->parsed() && !recolour->parsed() && !family->parsed()) runGather(*o);
    });

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
