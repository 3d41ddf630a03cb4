// weft — neural appearance model for cloth: command-line entry point.
#include <cstdio>
#include <exception>

#include "commands.h"
#include "weft/core/error.h"

int main(int argc, char** argv) {
    CLI::App app{
        "weft: fiber and ply models, RDM gathering, neural yarn fitting and cloth rendering.\n"
        "Run 'weft <command> --help' for the flags of one command.",
        "weft"};
    app.set_version_flag("--version", std::string("weft ") + WEFT_VERSION);
    app.require_subcommand(1);
    weft::cmd::addFiberCommands(app);
    weft::cmd::addPlyCommand(app);
    weft::cmd::addGatherCommand(app);
    weft::cmd::addFitCommand(app);
    weft::cmd::addYarnCommands(app);
    weft::cmd::addRenderCommand(app);
    weft::cmd::addCompareCommand(app);
    weft::cmd::addSceneCommand(app);
    weft::cmd::addMontageCommand(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        app.exit(e);
        return 2;
    } catch (const weft::InputError& e) {
        std::fprintf(stderr, "weft: error: %s\n", e.what());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "weft: internal error: %s\n", e.what());
        return 1;
    }
    return 0;
}
