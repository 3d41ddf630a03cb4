// Tests for weft/core/error.h: checkRange's bounds and wording.
#include "weft/core/error.h"

#include <gtest/gtest.h>

#include "weft/core/test_util.h"

namespace weft {
namespace {

TEST(CheckRange, AcceptsTheClosedRangeAndNamesValueAndBoundsOtherwise) {
    EXPECT_NO_THROW(checkRange("threads =", 0, 0, 1024));
    EXPECT_NO_THROW(checkRange("threads =", 1024, 0, 1024));
    EXPECT_NO_THROW(checkRange("--n", -5, -5, -5));
    testing::expectInputError([] { checkRange("threads =", 1025, 0, 1024, " (0: all cores)"); },
                              {"threads = 1025 is out of range: allowed [0, 1024] (0: all cores)"});
    testing::expectInputError([] { checkRange("--depth", -1, 1, 10000); },
                              {"--depth -1 is out of range: allowed [1, 10000]"});
    testing::expectInputError([] { checkRange("n =", int64_t(1) << 40, 1, int64_t(1) << 32); },
                              {"n = 1099511627776 is out of range: allowed [1, 4294967296]"});
}

}  // namespace
}  // namespace weft
