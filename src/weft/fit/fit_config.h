// weft/fit/fit_config.h — the configuration of weft fit (docs/fit.md).
//
// Network training (architecture, steps, batch, learning-rate schedule,
// loss) per network, and the switches of the other steps. Read strictly from
// JSON (unknown keys are errors naming the key; missing keys keep the
// defaults below); `weft fit --print-config` writes toJson().
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "weft/fit/mlp.h"
#include "weft/yarn/appearance_table.h"

namespace weft {

struct NetworkTraining {
    std::vector<int> hidden;          // hidden layer widths
    int64_t steps = 0;                // Adam steps
    int restarts = 1;                 // independent trainings from different seeds; the best is kept (T only)
    int batch = 0;                    // samples per step
    double learningRate = 1e-3;       // at step 0
    double finalLearningRate = 1e-5;  // at the last step (exponential decay in between)
    Loss loss = Loss::Mse;
};

struct FitConfig {
    NetworkTraining t{{7, 7}, 60000, 4, 512, 3e-2, 1e-5, Loss::Mse};
    NetworkTraining m{{21, 21, 21}, 150000, 1, 1024, 3e-3, 3e-5, Loss::Mse};
    bool jitter = true;     // train on random directions inside the bins (else bin centres)
    bool masking = true;    // fit the R masking term (else plain eq. 8)
    int calibrationDegree = 8;  // energy calibration polynomial degree; -1: none
    // A colour model's appearance table: greys over the colour range (step 6).
    int appearanceNodes = AppearanceTable::kDefaultNodes;
    // Where M light leaves the ply (model.json "exit_offset", version 5;
    // docs/exit-point.md), from the gather's exit_offset.npy, for a full model
    // of one colour; the renderer then moves the exit point. Off by default:
    // such a model renders at 1.5-1.7 times the time (docs/exit-point.md).
    bool exitOffset = false;
    int threads = 0;        // 0: all cores; never changes the result

    // Strict reading (unknown keys are errors naming the key); missing keys
    // keep the defaults. The result is validate()d.
    static FitConfig fromJson(const nlohmann::json& j, const std::string& source);
    static FitConfig fromJsonFile(const std::string& path);
    nlohmann::json toJson() const;

    // InputError naming `source` and the field unless the renderer can run
    // what this configuration fits: hidden widths within the T and M
    // evaluators' capacities (yarn/network_capacity.h), and an energy
    // calibration degree that a model file may hold (-1 or
    // [0, EnergyCalibration::kMaxDegree]). weft fit calls it before training.
    void validate(const std::string& source) const;
};

}  // namespace weft
