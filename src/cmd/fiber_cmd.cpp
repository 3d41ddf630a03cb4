// weft fiber eval | sample: probes of the fiber BCSDF on NumPy arrays.
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "weft/core/file.h"
#include "weft/core/error.h"
#include "weft/core/image.h"
#include "weft/core/math.h"
#include "weft/core/npy.h"
#include "weft/fiber/fiber_bcsdf.h"

namespace weft::cmd {

namespace {

struct EvalOptions {
    MaterialOptions material;
    std::string in, out;
};

struct SampleOptions {
    MaterialOptions material;
    std::string wi, out;
    int64_t count = 0;
    uint64_t seed = 0;
};

void runEval(const EvalOptions& o) {
    checkOutputsSpareInputs({{"--in", o.in}, {"--params", o.material.paramsFile}},
                            {{"--out", o.out}});
    const FiberBcsdf fiber(o.material.fiber());
    writeEvalValues(fiber, o.in, o.out);
}

void runSample(const SampleOptions& o) {
    checkOutputsSpareInputs({{"--params", o.material.paramsFile}}, {{"--out", o.out}});
    const FiberBcsdf fiber(o.material.fiber());
    const Vec3 wi = parseDirection(o.wi, "--wi");
    writeSamples(fiber, wi, o.count, o.seed, false, o.out);
}

struct MapOptions {
    MaterialOptions material;
    std::string wi, out;
    int width = 720;
};

// A latitude-longitude picture of eval(wi, .) in the fiber frame: x is the
// azimuth phi_o from -pi (left) to pi, y the longitudinal angle theta_o from
// +pi/2 (top, along the tangent) to -pi/2. Auto-exposed so that the 99th
// percentile of the values maps to white.
void runMap(const MapOptions& o) {
    checkOutputsSpareInputs({{"--params", o.material.paramsFile}}, {{"--out", o.out}});
    const FiberBcsdf fiber(o.material.fiber());
    const Vec3 wi = parseDirection(o.wi, "--wi");
    Image image(o.width, o.width / 2);
    std::vector<double> luminance;
    for (int y = 0; y < image.height; ++y) {
        const double theta = kHalfPi - kPi * (y + 0.5) / image.height;
        for (int x = 0; x < image.width; ++x) {
            const double phi = -kPi + kTwoPi * (x + 0.5) / image.width;
            const Vec3 wo{std::sin(theta), std::cos(theta) * std::cos(phi),
                          std::cos(theta) * std::sin(phi)};
            const Rgb f = fiber.eval(wi, wo);
            image.set(x, y, f);
            luminance.push_back(f.average());
        }
    }
    const size_t k = luminance.size() * 99 / 100;
    std::nth_element(luminance.begin(), luminance.begin() + k, luminance.end());
    const double white = luminance[k] > 0 ? luminance[k] : 1.0;
    writePng(o.out, image, -std::log2(white));
}

}  // namespace

void addFiberCommands(CLI::App& app) {
    CLI::App* fiber = app.add_subcommand(
        "fiber", "Probe the fiber BCSDF (Khungurn et al. 2015) in its local frame: tangent = +x, "
                 "azimuth in the y-z plane");
    fiber->require_subcommand(1);

    auto evalOpts = std::make_shared<EvalOptions>();
    CLI::App* eval = fiber->add_subcommand(
        "eval", "eval(wi, wo) RGB including cos(theta_o) for every row of an (n,6) array");
    evalOpts->material.add(*eval, false);
    eval->add_option("--in", evalOpts->in, "(n,6) float32/float64 .npy: rows wi(3), wo(3)")
        ->required();
    eval->add_option("--out", evalOpts->out, "(n,3) float64 .npy of RGB values")->required();
    eval->callback([evalOpts] { runEval(*evalOpts); });

    auto sampleOpts = std::make_shared<SampleOptions>();
    CLI::App* sample = fiber->add_subcommand(
        "sample", "draw outgoing directions for one wi: rows wo(3), weight RGB(3), pdf(1)");
    sampleOpts->material.add(*sample, false);
    sample->add_option("--wi", sampleOpts->wi, "incident direction X,Y,Z (normalised)")->required();
    sample->add_option("--count", sampleOpts->count, "number of samples")
        ->required()
        ->check(CLI::Range(int64_t{1}, int64_t{100000000}));
    addSeedOption(*sample, sampleOpts->seed, "random seed");
    sample->add_option("--out", sampleOpts->out, "(N,7) float64 .npy")->required();
    sample->callback([sampleOpts] { runSample(*sampleOpts); });

    auto mapOpts = std::make_shared<MapOptions>();
    CLI::App* map = fiber->add_subcommand(
        "map", "PNG of eval(wi, wo) over all wo: x = azimuth phi_o in [-pi, pi), "
               "y = theta_o from +90 (top) to -90 degrees");
    mapOpts->material.add(*map, false);
    map->add_option("--wi", mapOpts->wi, "incident direction X,Y,Z (normalised)")->required();
    map->add_option("--width", mapOpts->width, "image width; the height is half of it")
        ->default_val(720)
        ->check(CLI::Range(16, 8192));
    map->add_option("--out", mapOpts->out, "output PNG")->required();
    map->callback([mapOpts] { runMap(*mapOpts); });
}

}  // namespace weft::cmd
