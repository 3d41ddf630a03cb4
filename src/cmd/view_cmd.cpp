// weft view: the live page in the browser (issue 44, docs/view.md).
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "commands.h"
#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/view/view_server.h"

namespace weft::cmd {

namespace {

struct ViewCmdOptions {
    view::ViewOptions view;
    view::ServerOptions server;
    std::string modelsDir;
};

void runView(const ViewCmdOptions& o) {
    o.server.validate();
    view::ViewOptions options = o.view;
    options.presetsDir = view::presetsDir(o.modelsDir, "--models-dir");
    view::ViewSession session(options);
    view::ViewServer server(session, o.server);
    if (!o.server.loopback())
        std::fprintf(stderr,
                     "weft: warning: serving on %s, not only this machine: anyone who reaches "
                     "this address can use the page (and save into %s)\n",
                     o.server.host.c_str(), options.outDir.c_str());
    std::printf("weft view: %s (%s; Ctrl-C stops)\n", server.url().c_str(),
                options.scenePath.c_str());
    std::fflush(stdout);
    const StopOnSignal stop("nothing more");
    while (StopOnSignal::signal() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    server.stop();
    session.stop();
    std::fprintf(stderr, "weft view: stopped\n");
}

}  // namespace

void addViewCommand(CLI::App& app) {
    auto o = std::make_shared<ViewCmdOptions>();
    o->view.outDir = "weft-view";
    CLI::App* cmd = app.add_subcommand(
        "view",
        "Serve a live page in the browser that renders the scene progressively in neural mode "
        "while you orbit, change yarns, colours and lights, and compare with the fibers "
        "(docs/view.md)");
    cmd->add_option("scene", o->view.scenePath, "Scene file (scene.json)")->required();
    cmd->add_option("--port", o->server.port, "Port to listen on, [0, 65535] (0: any free port)")
        ->capture_default_str();
    cmd->add_option("--bind", o->server.host,
                    "Address to listen on (another than 127.0.0.1 lets other machines in: "
                    "weft warns)")
        ->capture_default_str();
    cmd->add_option("--out", o->view.outDir,
                    "Folder Save writes into (view-NNNN.json, .exr, .png; never over a file)")
        ->capture_default_str();
    cmd->add_option("--model", o->view.models,
                    "A model.json the page may choose (repeatable), besides the scene's own and "
                    "the presets");
    cmd->add_option("--models-dir", o->modelsDir,
                    "Folder of preset models the page offers (default: $WEFT_MODELS_DIR, or "
                    "the models/ weft was built with)");
    cmd->add_option("--spp", o->view.sppCap,
                    "Samples per pixel at which the view stops refining (0: the scene's "
                    "render.spp), [0, 65536]")
        ->capture_default_str();
    cmd->add_option("--threads", o->view.threads, "Render threads, [0, 1024] (0: all cores)")
        ->capture_default_str();
    cmd->callback([o] { runView(*o); });
}

}  // namespace weft::cmd
