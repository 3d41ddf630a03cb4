// weft — neural appearance model for cloth: command-line entry point.
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <exception>
#include <new>
#include <string>

#include "commands.h"
#include "unknown_command.h"
#include "weft/core/error.h"
#include "weft/core/file.h"

namespace {

// The summary line on stdout, flushed while an error can still be reported:
// stdout redirected into a file over the file-size limit (SIGXFSZ is
// ignored) or on a full disk must not end in status 0 with the line cut.
void flushStandardOutput() {
    errno = 0;
    if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
        const int err = errno;
        throw weft::InputError("cannot write the standard output: " +
                               (err != 0 ? weft::writeErrorText(err) : std::string("write error")));
    }
}

}  // namespace

int main(int argc, char** argv) {
    // SIGINT, SIGTERM and SIGHUP delete the temporary outputs being written
    // and end the process by the same signal (core/file.h); first thing, so
    // that every thread inherits the blocked mask.
    weft::removeTemporaryOutputsOnSignals();
    // Past the file-size limit (RLIMIT_FSIZE: ulimit -f, prlimit --fsize) a
    // write then fails with EFBIG, reported as "file too large" and cleaned up
    // like a full disk, instead of SIGXFSZ killing the process (status 153)
    // with its temporary outputs in place.
    std::signal(SIGXFSZ, SIG_IGN);
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
    weft::cmd::addCurvesCommands(app);
    weft::cmd::addViewCommand(app);
    try {
        try {
            app.parse(argc, argv);
        } catch (const weft::cmd::ExitStatus& e) {
            flushStandardOutput();
            return e.status;
        }
        flushStandardOutput();
    } catch (const CLI::CallForHelp& e) {
        if (weft::cmd::reportUnknownCommand(app)) return 2;  // `weft view --help`
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        if (weft::cmd::reportUnknownCommand(app)) return 2;
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        if (weft::cmd::reportUnknownCommand(app)) return 2;
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        if (weft::cmd::reportUnknownCommand(app)) return 2;
        app.exit(e);
        return 2;
    } catch (const weft::InputError& e) {
        std::fprintf(stderr, "weft: error: %s\n", e.what());
        return 2;
    } catch (const std::bad_alloc&) {
        // The budgets (core/limits.h) refuse what they can estimate; this is what they missed.
        std::fprintf(stderr,
                     "weft: error: out of memory: the input needs more memory than this machine "
                     "has (docs/limits.md; WEFT_MEMORY_BUDGET)\n");
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "weft: internal error: %s\n", e.what());
        return 1;
    }
    return 0;
}
