// weft/yarn/highway_targets.h — one result per Highway target, for the tests
// that hold every compiled SIMD kernel to its reference (fixed_mlp.h,
// packed_calibration.h).
#pragma once

#include <hwy/targets.h>

#include <cstdint>
#include <vector>

namespace weft {

// select() (a HWY_DYNAMIC_DISPATCH call) once per instruction set that this
// CPU runs and Highway compiled, best first; dispatch is restored afterwards.
template <typename Select>
auto everyHighwayTarget(const Select& select) {
    std::vector<decltype(select())> results;
    for (const int64_t target : hwy::SupportedAndGeneratedTargets()) {
        hwy::SetSupportedTargetsForTest(target);
        results.push_back(select());
    }
    hwy::SetSupportedTargetsForTest(0);
    return results;
}

}  // namespace weft
