// weft command line: an unknown command is an error naming it (exit status
// 2), with or without --help after it (issue 41: `weft view --help` printed
// the main help with status 0).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace weft::cmd {

// "unknown command 'view' for 'weft'; the commands are: fiber, ply, ..."
// for the first argument that was left over where a command name was
// expected: by `app` or a command parsed under it that has subcommands, none
// of them given, and no positional argument that could have taken it
// (`weft view`, `weft curves bogus --help`). "" when there is none; options
// (a leading '-') are left to CLI11's own messages.
std::string unknownCommand(const CLI::App& app);

// Prints "weft: error: <unknownCommand(app)>" on stderr and returns true when
// there is one: main()'s parse error and help handlers call it first.
bool reportUnknownCommand(const CLI::App& app);

}  // namespace weft::cmd
