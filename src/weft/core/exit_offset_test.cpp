// The exit-offset layout (core/exit_offset.h): cells and slots at their edges.
#include "weft/core/exit_offset.h"

#include <gtest/gtest.h>

#include <limits>

#include "weft/core/math.h"

namespace weft {
namespace {

TEST(ExitOffset, CellsAndSlotsAtTheirEdges) {
    // Cells: theta_i from n in 4 bands, phi_i from t towards b in 8.
    EXPECT_EQ(exitOffsetCell({0, 0, 1}), size_t{0} * kExitOffsetPhi + 4);  // phi 0: band 4
    EXPECT_EQ(exitOffsetCell(normalize(Vec3{0, -1, 0.01})), size_t{3} * kExitOffsetPhi + 2);
    EXPECT_EQ(exitOffsetCell(normalize(Vec3{-1, -1e-9, 2})), size_t{1} * kExitOffsetPhi + 0);
    // Slots: dz centred on 0, dpsi over [-pi, pi), beyond the axial range last.
    const int mid = kExitOffsetAxialBins / 2;
    EXPECT_EQ(exitOffsetSlot(0.01, 0.01),
              static_cast<size_t>(mid) * kExitOffsetAroundBins + kExitOffsetAroundBins / 2);
    EXPECT_EQ(exitOffsetSlot(-0.01, -kPi), static_cast<size_t>(mid - 1) * kExitOffsetAroundBins);
    EXPECT_EQ(exitOffsetSlot(mid * kExitOffsetAxialWidth, 0.0), kExitOffsetSlots - 1);
    EXPECT_EQ(exitOffsetSlot(-mid * kExitOffsetAxialWidth, kPi),
              static_cast<size_t>(kExitOffsetAroundBins) - 1);
    EXPECT_EQ(exitOffsetSlot(std::numeric_limits<double>::infinity(), 0.0), kExitOffsetSlots - 1);
}

}  // namespace
}  // namespace weft
