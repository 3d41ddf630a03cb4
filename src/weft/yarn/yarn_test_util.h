// weft/yarn/yarn_test_util.h — yarn models for the tests of yarn/ and fit/.
#pragma once

#include <cmath>
#include <string>

#include "weft/yarn/yarn_model.h"

namespace weft::testing {

// The committed test models (tests/data/README.md): "fleece-small", "gabardine-small".
inline std::string testModelPath(const std::string& name) {
    return std::string(WEFT_SOURCE_DIR) + "/tests/data/" + name + ".json";
}

// `model` with a hand-set energy calibration: S_R times 1/2 and S_M times 2 exp(0.3 x).
inline YarnModel withCalibration(YarnModel model) {
    model.calibration.degree = 1;
    for (int c = 0; c < 3; ++c) {
        model.calibration.r[c] = {-std::log(2.0), 0, 0, 0};
        model.calibration.m[c] = {std::log(2.0), 0, 0, 0.3};  // 1, z, y, x
    }
    return model;
}

}  // namespace weft::testing
