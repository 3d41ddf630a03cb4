#include "unknown_command.h"

#include <cstdio>
#include <string>
#include <vector>

namespace weft::cmd {

namespace {

// "weft curves": the names from the top-level app down to `app`.
std::string commandPath(const CLI::App& app) {
    const CLI::App* parent = app.get_parent();
    return parent ? commandPath(*parent) + " " + app.get_name() : app.get_name();
}

}  // namespace

std::string unknownCommand(const CLI::App& app) {
    for (const CLI::App* sub : app.get_subcommands())
        if (std::string message = unknownCommand(*sub); !message.empty()) return message;
    const std::vector<const CLI::App*> commands =
        app.get_subcommands([](const CLI::App*) { return true; });
    if (commands.empty() || !app.get_subcommands().empty()) return "";
    if (!app.get_options([](const CLI::Option* o) { return o->get_positional(); }).empty())
        return "";
    for (const std::string& arg : app.remaining()) {
        if (!arg.empty() && arg[0] == '-') continue;
        std::string names;
        for (const CLI::App* c : commands) names += (names.empty() ? "" : ", ") + c->get_name();
        return "unknown command '" + arg + "' for '" + commandPath(app) +
               "'; the commands are: " + names;
    }
    return "";
}

bool reportUnknownCommand(const CLI::App& app) {
    const std::string message = unknownCommand(app);
    if (message.empty()) return false;
    std::fprintf(stderr, "weft: error: %s\n", message.c_str());
    return true;
}

}  // namespace weft::cmd
