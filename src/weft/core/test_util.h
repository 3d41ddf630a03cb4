// weft/core/test_util.h — helpers shared by the *_test.cpp files.
#pragma once

#include <cstdint>

namespace weft::testing {

// Monte Carlo sample counts in tests are multiplied by this; the sanitizer
// build (WEFT_SANITIZE) runs the same tests with fewer samples.
constexpr double sampleScale() {
#ifdef WEFT_SANITIZED
    return 0.1;
#else
    return 1.0;
#endif
}

constexpr int64_t scaled(int64_t n) {
    const auto s = static_cast<int64_t>(n * sampleScale());
    return s < 1000 ? 1000 : s;
}

}  // namespace weft::testing
