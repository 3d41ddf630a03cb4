// weft command line: one binary, one registration function per subcommand group.
//
// Each add*Command() declares its flags on a CLI11 subcommand and installs a
// callback that validates them and calls the library. User errors are thrown
// as weft::InputError; main() turns them into "weft: error: ..." and exit 2.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "weft/core/npy.h"
#include "weft/fiber/fiber_params.h"

namespace weft::cmd {

// --preset NAME | --params FILE, shared by every command that needs fiber parameters.
struct MaterialOptions {
    std::string preset;
    std::string paramsFile;

    void add(CLI::App& app, bool withPly);
    // The fiber parameters named by the flags; InputError when neither or both are given.
    FiberParams fiber() const;
};

// --fibers N --density RHO --twist ALPHA: explicit ply geometry (paper eq. 1).
struct PlyGeometryOptions {
    int fibers = 0;
    double density = 0, twist = 0;
    CLI::Option *fibersOpt = nullptr, *densityOpt = nullptr, *twistOpt = nullptr;

    void add(CLI::App& app);
    bool anyGiven() const { return fibersOpt->count() || densityOpt->count() || twistOpt->count(); }
    bool allGiven() const { return fibersOpt->count() && densityOpt->count() && twistOpt->count(); }
    PlyParams params() const { return {fibers, density, twist}; }
};

// Parses "X,Y,Z" into three finite numbers; InputError naming `flag` otherwise.
Vec3 parseVec3(const std::string& text, const std::string& flag);
// parseVec3, then normalised (any non-zero finite vector, however large or small).
Vec3 parseDirection(const std::string& text, const std::string& flag);

// Row `row`, columns col..col+2 of an (n, 6) PAIRS array as a unit vector
// (wi at col 0, wo at col 3): length within 1e-3 of 1 (float32 inputs),
// renormalised; InputError naming `path` and the row otherwise.
Vec3 unitVectorAt(const NpyMatrix& m, size_t row, size_t col, const std::string& path);

// Adds a seed flag (an unsigned 64-bit integer, default 0; negative values are
// refused instead of wrapping around) to a command.
CLI::Option* addSeedOption(CLI::App& app, uint64_t& seed, const std::string& description,
                           const std::string& flag = "--seed");

void addFiberCommands(CLI::App& app);
void addPlyCommand(CLI::App& app);
void addGatherCommand(CLI::App& app);
void addFitCommand(CLI::App& app);
void addYarnCommands(CLI::App& app);

}  // namespace weft::cmd
