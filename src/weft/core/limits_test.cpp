#include "weft/core/limits.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include "weft/core/test_util.h"

namespace weft {
namespace {

using testing::expectInputError;

TEST(Limits, ByteSizesWithSuffixes) {
    EXPECT_EQ(parseByteSize("1", "X"), 1u);
    EXPECT_EQ(parseByteSize("512M", "X"), uint64_t{512} << 20);
    EXPECT_EQ(parseByteSize("16g", "X"), uint64_t{16} << 30);
    EXPECT_EQ(parseByteSize("2T", "X"), uint64_t{2} << 40);
    for (const char* bad :
         {"", "0", "-1", "1.5G", "12Q", "G", "1GB", "99999999999999999999", "8000000000T"})
        expectInputError([&] { parseByteSize(bad, "WEFT_X"); }, {"WEFT_X = \"", "suffix"});
}

TEST(Limits, ByteTextReadsAsPeopleSayIt) {
    EXPECT_EQ(byteText(80), "80 bytes");
    EXPECT_EQ(byteText(12e3), "12 KB");
    EXPECT_EQ(byteText(7.2e9), "7.2 GB");
    EXPECT_EQ(byteText(850e6), "850 MB");
}

TEST(Limits, MemoryBudgetFromTheEnvironment) {
    ASSERT_EQ(::setenv("WEFT_MEMORY_BUDGET", "1G", 1), 0);
    EXPECT_EQ(memoryBudgetBytes(), uint64_t{1} << 30);
    checkMemoryBudget(1e9, "the bins");
    expectInputError([] { checkMemoryBudget(7.2e9, "the RDM's bins"); },
                     {"the RDM's bins needs about 7.2 GB, over the memory budget of 1.1 GB",
                      "WEFT_MEMORY_BUDGET"});
    expectInputError([] { checkMemoryBudget(1e300, "x"); }, {"over the memory budget"});
    ::unsetenv("WEFT_MEMORY_BUDGET");
    // The default: 3/4 of the physical memory, which any test machine has.
    EXPECT_GT(memoryBudgetBytes(), uint64_t{256} << 20);
}

}  // namespace
}  // namespace weft
