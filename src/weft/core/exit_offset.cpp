#include "weft/core/exit_offset.h"

#include <algorithm>
#include <cmath>

#include "weft/core/math.h"

namespace weft {

size_t exitOffsetCell(const Vec3& wiLocal) {
    const double theta = safeAcos(wiLocal.z), phi = std::atan2(wiLocal.y, wiLocal.x);
    const int a =
        std::clamp(static_cast<int>(theta / kHalfPi * kExitOffsetTheta), 0, kExitOffsetTheta - 1);
    const int b =
        std::clamp(static_cast<int>((phi + kPi) / kTwoPi * kExitOffsetPhi), 0, kExitOffsetPhi - 1);
    return static_cast<size_t>(a) * kExitOffsetPhi + b;
}

size_t exitOffsetSlot(double dz, double dpsi) {
    const double axial = dz / kExitOffsetAxialWidth + 0.5 * kExitOffsetAxialBins;
    if (!(axial >= 0 && axial < kExitOffsetAxialBins)) return kExitOffsetSlots - 1;
    const int around = std::clamp(static_cast<int>((dpsi + kPi) / kTwoPi * kExitOffsetAroundBins),
                                  0, kExitOffsetAroundBins - 1);
    return static_cast<size_t>(axial) * kExitOffsetAroundBins + around;
}

}  // namespace weft
