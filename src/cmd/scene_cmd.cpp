// weft scene: a generated close-up, plain weave or stockinette knit scene for
// `weft render` (docs/scenes.md).
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "commands.h"
#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/text_parse.h"
#include "weft/eval/scene_gen.h"
#include "weft/render/mitsuba.h"
#include "weft/render/scene_file.h"

namespace weft::cmd {

namespace {

struct SceneCmdOptions {
    std::string kind, out, curves, view = "three-quarter";
    CLI::Option* radiusOpt = nullptr;
    eval::SceneOptions scene;
    std::vector<std::string> colours;      // --colours: "R,G,B" each
    std::vector<std::string> appearances;  // --appearance: "#rrggbb" or "R,G,B" each
    std::string yarn;                      // --yarn: JSON text or file
    CLI::Option* sizeOpt = nullptr;
    CLI::Option* stripeOpt = nullptr;
    int stripe = eval::kDefaultStripe;
    CLI::Option* dyeLengthOpt = nullptr;
    double dyeLength = 0;
    bool quiet = false;
    // import / export (Mitsuba 3, docs/mitsuba.md)
    std::string models, mitsuba;
    std::vector<std::string> defines;  // NAME=VALUE
    bool fibers = false;
};

void printNotes(const std::vector<std::string>& notes) {
    for (const std::string& n : notes) std::fprintf(stderr, "weft: note: %s\n", n.c_str());
}

// weft scene import SCENE.xml --out DIR [--model M | --models MAP.json] [--define N=V]
void runImport(const SceneCmdOptions& o) {
    if (o.curves.empty())
        throw InputError(
            "weft scene import needs the Mitsuba scene: weft scene import SCENE.xml "
            "--out DIR [--model MODEL.json | --models MAP.json]");
    if (o.out.empty()) throw InputError("weft scene import needs --out DIR");
    render::MitsubaImportOptions options;
    options.model = o.scene.model;
    options.mapping = o.models;
    for (const std::string& d : o.defines) {
        const size_t eq = d.find('=');
        if (eq == 0 || eq == std::string::npos)
            throw InputError("--define " + d + ": expected NAME=VALUE");
        options.defines.push_back({d.substr(0, eq), d.substr(eq + 1)});
    }
    checkOutputsSpareInputs(
        {{"SCENE", o.curves}, {"--model", o.scene.model}, {"--models", o.models}}, {}, {},
        {{"--out", o.out}});
    const render::MitsubaImport imported = render::importMitsubaScene(o.curves, options);
    std::vector<std::pair<std::string, std::string>> files = imported.files;
    files.push_back({"scene.json", imported.scene.dump(2) + "\n"});
    render::writeSceneFolder(files, o.out);
    printNotes(imported.notes);
    std::printf("%s\n", nlohmann::json({{"scene", o.out + "/scene.json"},
                                        {"yarns", imported.scene["yarns"].size()},
                                        {"lights", imported.scene["lights"].size()},
                                        {"notes", imported.notes.size()}})
                            .dump()
                            .c_str());
}

// weft scene export SCENE.json --mitsuba DIR [--fibers]
void runExport(const SceneCmdOptions& o) {
    if (o.curves.empty() || o.mitsuba.empty())
        throw InputError(
            "weft scene export needs the scene and the folder: weft scene export "
            "SCENE.json --mitsuba DIR [--fibers]");
    const render::SceneDesc scene = render::loadScene(o.curves);
    checkOutputsSpareInputs(render::sceneInputs(scene, o.curves), {}, {},
                            {{"--mitsuba", o.mitsuba}});
    const render::MitsubaExport exported = render::exportMitsubaScene(scene, o.fibers);
    render::writeSceneFolder(exported.files, o.mitsuba);
    printNotes(exported.notes);
    std::printf("%s\n", nlohmann::json({{"scene", o.mitsuba + "/scene.xml"},
                                        {"files", exported.files.size()},
                                        {"notes", exported.notes.size()}})
                            .dump()
                            .c_str());
}

void runScene(SceneCmdOptions o) {
    if (o.kind == "import") return runImport(o);
    if (o.kind == "export") return runExport(o);
    if (o.kind != "closeup" && o.kind != "weave" && o.kind != "knit" && o.kind != "curves")
        throw InputError("unknown scene kind \"" + o.kind +
                         "\": allowed closeup, weave, knit, curves, import, export");
    for (const auto& [flag, given] : {std::pair<const char*, bool>{"--models", !o.models.empty()},
                                      {"--define", !o.defines.empty()},
                                      {"--mitsuba", !o.mitsuba.empty()},
                                      {"--fibers", o.fibers}})
        if (given) throw InputError(std::string(flag) + " applies to weft scene import or export");
    if (o.scene.model.empty()) throw InputError("--model is required");
    if (o.out.empty()) throw InputError("--out is required");
    const eval::SceneKind kind = eval::parseSceneKind(o.kind);
    if (kind == eval::SceneKind::Closeup && o.sizeOpt->count())
        throw InputError("--size applies to weave and knit only (a close-up is one yarn)");
    if (kind == eval::SceneKind::Curves) {
        if (o.curves.empty())
            throw InputError(
                "weft scene curves needs the curve file: weft scene curves FILE "
                "--model MODEL.json --out DIR");
        if (o.sizeOpt->count())
            throw InputError(
                "--size applies to weave and knit only (curves draws the file's yarns)");
        o.scene.curves = o.curves;
        o.scene.view = eval::parseCurvesView(o.view);
        // --radius is in the file's units here; the scene's radius stays the default.
        if (o.radiusOpt->count()) o.scene.curveRadius = o.scene.radius;
        o.scene.radius = eval::SceneOptions{}.radius;
    } else if (!o.curves.empty()) {
        throw InputError("a curve file (" + o.curves + ") applies to weft scene curves only");
    }
    if (o.stripeOpt->count()) o.scene.stripe = o.stripe;
    // Given means checked (SceneOptions::validate), 0 included.
    if (o.dyeLengthOpt->count()) o.scene.dyeLength = o.dyeLength;
    for (const std::string& c : o.colours) o.scene.colours.push_back(parseColour(c, "--colours"));
    for (const std::string& c : o.appearances)
        o.scene.appearances.push_back(parseSrgbColour(c, "--appearance"));
    if (!o.yarn.empty()) o.scene.yarn = readYarnPointArgument(o.yarn, "--yarn");
    checkOutputsSpareInputs(
        {{"--model", o.scene.model}, {"--envmap", o.scene.envmap}, {"FILE", o.curves}}, {}, {},
        {{"--out", o.out}});
    const eval::GeneratedScene generated = eval::generateScene(kind, o.scene);
    eval::writeScene(generated, o.out);
    std::vector<std::string> warnings;
    const nlohmann::json summary = eval::sceneSummary(generated, kind, o.out, &warnings);
    if (!o.quiet)
        for (const std::string& w : warnings)
            std::fprintf(stderr, "weft: warning: %s\n", w.c_str());
    // Printed with --quiet too: the scene as written will not render neural.
    for (const std::string& w : generated.colourWarnings)
        std::fprintf(stderr, "weft: warning: %s\n", w.c_str());
    std::printf("%s\n", summary.dump().c_str());
}

}  // namespace

void addSceneCommand(CLI::App& app) {
    auto o = std::make_shared<SceneCmdOptions>();
    eval::SceneOptions& s = o->scene;
    CLI::App* cmd = app.add_subcommand(
        "scene",
        "Write a generated scene (docs/scenes.md) for `weft render`: DIR/scene.json and "
        "DIR/yarns.txt (DIR/yarns-1.txt, yarns-2.txt with two colours). closeup: one 3-ply "
        "yarn across the frame; weave: an N x N plain weave; knit: N courses of N "
        "stockinette loops; curves FILE: your own curve file framed whole (yarns.bcc). "
        "import SCENE.xml: a Mitsuba 3 scene as a weft scene folder; export SCENE.json "
        "--mitsuba DIR: a weft scene as a Mitsuba 3 scene (docs/mitsuba.md).");
    cmd->add_option("kind", o->kind, "closeup, weave, knit, curves, import or export")->required();
    cmd->add_option("file", o->curves,
                    "curves: the curve file (.bcc, .txt, .obj; docs/curves.md), drawn whole; "
                    "import: the Mitsuba SCENE.xml; export: the weft SCENE.json");
    cmd->add_option("--view", o->view,
                    "curves: where the camera looks from: three-quarter (35 degrees right of the "
                    "front, 30 above), front (from +z) or top (from +y)")
        ->capture_default_str();
    cmd->add_option("--model", s.model,
                    "MODEL.json written by `weft fit` (must load); import: the model of every "
                    "curve shape the --models file does not map");
    cmd->add_option("--models", o->models,
                    "import: MAP.json, bsdf id -> yarn keys (model, plies, ply_twist, colour, "
                    "...; docs/mitsuba.md); default: weft-models.json beside the XML");
    cmd->add_option("--define", o->defines,
                    "import: NAME=VALUE for $NAME in the XML, over its <default> (repeatable)");
    cmd->add_option("--mitsuba", o->mitsuba, "export: the output folder of the Mitsuba 3 scene");
    cmd->add_flag("--fibers", o->fibers,
                  "export: the explicit fibers of fiber mode as the curves, not the yarns");
    o->sizeOpt = cmd->add_option("--size", s.size,
                                 "weave: N warp and N weft yarns; knit: N courses of N loops; "
                                 "[1, 100]")
                     ->capture_default_str();
    o->radiusOpt = cmd->add_option("--radius", s.radius,
                                   "Yarn radius in scene units, [1e-6, 1000]; for curves in the "
                                   "file's units (default: the largest radius at which no yarns "
                                   "overlap, weft curves info), the scene then scaled so that it "
                                   "is 0.01")
                       ->capture_default_str();
    cmd->add_option("--plies", s.plies, "Plies per yarn, [1, 16]")->capture_default_str();
    cmd->add_option("--ply-twist", s.plyTwist,
                    "Dimensionless ply twist (scene ply_twist), [-100, 100]")
        ->capture_default_str();
    cmd->add_option("--width", s.width, "Film width in pixels, [1, 16384]")->capture_default_str();
    cmd->add_option("--height", s.height, "Film height in pixels, [1, 16384]")
        ->capture_default_str();
    cmd->add_option("--spp", s.spp, "Samples per pixel (render.spp), [1, 1048576]")
        ->capture_default_str();
    cmd->add_option("--envmap", s.envmap,
                    "Lat-long .exr or .hdr environment map instead of the procedural sky");
    cmd->add_option("--colours", o->colours,
                    "One or two fiber colours C_TT as R,G,B in [0, 1] (docs/colour.md): one "
                    "colours every yarn; two make a striped knit or a check weave. Neural mode "
                    "needs a colour model (weft fit --colour-range) and each colour within its "
                    "range: weft scene warns otherwise");
    cmd->add_option("--appearance", o->appearances,
                    "Instead of --colours: one or two colours the yarns should look, sRGB, "
                    "#rrggbb or R,G,B in [0, 1] (docs/colour.md, \"Colour by appearance\"); "
                    "needs a colour model, and each colour within the material's reach");
    cmd->add_option("--yarn", o->yarn,
                    "With a family model (weft fit family): the yarn, YARN.json or inline "
                    "{\"fibers\", \"density\", \"twist\", \"beta_r_deg\", \"beta_tt_deg\", "
                    "\"gamma_tt_deg\", \"c_r\"}, inside the family's box (docs/family.md)");
    o->stripeOpt = cmd->add_option("--stripe", o->stripe,
                                   "With two colours: knit courses or weave yarns per stripe, "
                                   "[1, 100]")
                       ->capture_default_str();
    o->dyeLengthOpt = cmd->add_option("--dye-length", o->dyeLength,
                                      "With two colours: space-dyed yarns instead of stripes, "
                                      "the colour alternating every L yarn radii along each "
                                      "yarn (a vertex colour file), [0.5, 10000]");
    cmd->add_flag("--floor", s.floor,
                  "Add a diffuse grey floor (scene \"objects\", docs/scene-format.md): under the "
                  "cloth for curves, behind the patch for the other kinds");
    cmd->add_flag("--quiet", o->quiet, "No warning when the generated yarns overlap");
    cmd->add_option("--out", o->out,
                    "Output directory (replaced only if it holds nothing but an earlier "
                    "scene)");
    cmd->callback([o] { runScene(*o); });
}

}  // namespace weft::cmd
