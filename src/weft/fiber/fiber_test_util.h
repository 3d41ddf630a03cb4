// weft/fiber/fiber_test_util.h — fiber parameters for the tests of fiber/ and gather/.
//
// The fiber half of each row of the paper's Table 3 (docs/design.md 3), as test
// inputs that span narrow and wide lobes, dark and bright fibers. The
// material presets themselves (yarn/material_preset.h) add the ply geometry
// and sit above fiber/ and ply/, where these tests may not reach.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "weft/fiber/fiber_params.h"

namespace weft::testing {

struct NamedFiber {
    std::string_view name;
    FiberParams fiber;
};

// C_R; C_TT; beta_R, beta_TT, gamma_TT (degrees) of fleece, silk, polyester,
// cotton and gabardine.
inline const std::vector<NamedFiber>& table3Fibers() {
    static const std::vector<NamedFiber> fibers = {
        {"fleece", {{0.040, 0.087, 0.087}, {0.452, 0.725, 0.948}, 7.238, 10.000, 25.989}},
        {"silk", {{0.745, 0.008, 0.070}, {0.620, 0.553, 0.562}, 1.000, 10.000, 19.823}},
        {"polyester", {{0.700, 0.700, 0.700}, {0.600, 0.000, 0.800}, 5.238, 20.000, 25.000}},
        {"cotton", {{0.989, 0.959, 0.874}, {0.999, 0.999, 0.999}, 1.000, 27.197, 38.269}},
        {"gabardine", {{0.185, 0.047, 0.069}, {0.999, 0.330, 0.354}, 2.141, 10.000, 23.548}},
    };
    return fibers;
}

// The fibers of one material of table3Fibers(); a test bug (std::logic_error) for another name.
inline const FiberParams& table3Fiber(std::string_view name) {
    for (const NamedFiber& f : table3Fibers())
        if (f.name == name) return f.fiber;
    throw std::logic_error("no Table 3 test fiber named " + std::string(name));
}

}  // namespace weft::testing
