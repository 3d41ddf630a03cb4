// weft command line: one binary, one registration function per subcommand group.
//
// Each add*Command() declares its flags on a CLI11 subcommand and installs a
// callback that validates them and calls the library. User errors are thrown
// as weft::InputError; main() turns them into "weft: error: ..." and exit 2.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>
#include <vector>

#include "weft/core/bsdf.h"
#include "weft/core/family_box.h"
#include "weft/core/npy.h"
#include "weft/core/rng.h"
#include "weft/fiber/fiber_params.h"
#include "weft/ply/ply.h"

namespace weft::cmd {

// Thrown by a command that wrote its outputs and must still end with a status
// other than 0 (weft render stopped by a signal: 128 + the signal); main()
// returns `status` after flushing the summary line.
struct ExitStatus {
    int status;
};

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

// weft {fiber,yarn} eval: bsdf.eval for every row of the (n, 6) PAIRS file
// `in`, written to `out` as (n, 3) float64.
template <typename Bsdf>
void writeEvalValues(const Bsdf& bsdf, const std::string& in, const std::string& out) {
    const NpyMatrix pairs = readNpyMatrix(in, 6, "wi, wo pairs");
    std::vector<double> values(pairs.rows * 3);
    for (size_t i = 0; i < pairs.rows; ++i) {
        const Rgb f = bsdf.eval(unitVectorAt(pairs, i, 0, in), unitVectorAt(pairs, i, 3, in));
        for (int c = 0; c < 3; ++c) values[3 * i + c] = f[c];
    }
    writeNpy(out, values.data(), {pairs.rows, 3});
}

// weft {fiber,yarn} sample: `count` samples for wi, rows wo (3), weight RGB
// (3), pdf (1) and, with `withLobe`, the lobe id (1), written as float64.
template <typename Bsdf>
void writeSamples(const Bsdf& bsdf, const Vec3& wi, int64_t count, uint64_t seed, bool withLobe,
                  const std::string& out) {
    const size_t columns = withLobe ? 8 : 7;
    std::vector<double> rows(static_cast<size_t>(count) * columns);
    for (int64_t i = 0; i < count; ++i) {
        // One stream per sample index: the output does not depend on chunking.
        Rng rng(static_cast<uint64_t>(i), seed);
        const BsdfSampleInput u = {rng.uniform(), rng.uniform(), rng.uniform()};
        const BsdfSample s = bsdf.sample(wi, u, rng);
        double* r = &rows[columns * static_cast<size_t>(i)];
        r[0] = s.wo.x, r[1] = s.wo.y, r[2] = s.wo.z;
        r[3] = s.weight.r, r[4] = s.weight.g, r[5] = s.weight.b;
        r[6] = s.pdf;
        if (withLobe) r[7] = s.lobe;
    }
    writeNpy(out, rows.data(), {static_cast<size_t>(count), columns});
}

// Refuses a negative seed, which CLI11 would wrap around to 2^64 - 1.
CLI::Validator seedValidator();
// Adds a seed flag (an unsigned 64-bit integer, default 0; negative values are
// refused instead of wrapping around) to a command.
CLI::Option* addSeedOption(CLI::App& app, uint64_t& seed, const std::string& description,
                           const std::string& flag = "--seed");

void addFiberCommands(CLI::App& app);
void addPlyCommand(CLI::App& app);
void addGatherCommand(CLI::App& app);
void addFitCommand(CLI::App& app);
void addYarnCommands(CLI::App& app);
void addRenderCommand(CLI::App& app);
void addCompareCommand(CLI::App& app);
void addSceneCommand(CLI::App& app);
void addMontageCommand(CLI::App& app);
void addCurvesCommands(CLI::App& app);
void addViewCommand(CLI::App& app);

// A yarn of a family (core/family_box.h) from a flag's value: inline JSON
// (starting with "{") or a JSON file; InputError naming the flag or file.
YarnPoint readYarnPointArgument(const std::string& text, const std::string& flag);

}  // namespace weft::cmd
