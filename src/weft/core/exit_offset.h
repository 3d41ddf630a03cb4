// weft/core/exit_offset.h — the layout of exit offsets (issue 47,
// docs/exit-point.md): where a ply's multiply scattered (M) light leaves it
// relative to where it entered, on the ply's bounding cylinder of radius 1,
// in the yarn frame of the entry point (docs/design.md 2: t along the axis,
// n outward, b = t x n). The gather bins its paths by it and the runtime
// model samples on it, so the one convention lives here.
//
//   dz    the offset along the axis, in ply radii, positive along t (z
//         unwrapped across twist periods);
//   dpsi  the angle around the axis, in [-pi, pi), positive from n towards
//         b (on the unit cylinder: ply radii of arc).
// Incident cells: kExitOffsetTheta equal bands of theta_i (the polar angle
// from n, [0, pi/2]) times kExitOffsetPhi of phi_i (the azimuth from t
// towards b, [-pi, pi)), theta-major. Slots of a cell: kExitOffsetAxialBins
// bins of dz, kExitOffsetAxialWidth wide and centred on 0, times
// kExitOffsetAroundBins equal bins of dpsi, row-major (dz rows), then one
// slot for offsets beyond the axial range (and paths that ran along it).
#pragma once

#include <cstddef>

#include "weft/core/vec.h"

namespace weft {

inline constexpr int kExitOffsetTheta = 4, kExitOffsetPhi = 8;
inline constexpr int kExitOffsetAxialBins = 128, kExitOffsetAroundBins = 64;
inline constexpr double kExitOffsetAxialWidth = 0.125;
inline constexpr size_t kExitOffsetCells = static_cast<size_t>(kExitOffsetTheta) * kExitOffsetPhi;
inline constexpr size_t kExitOffsetSlots =
    static_cast<size_t>(kExitOffsetAxialBins) * kExitOffsetAroundBins + 1;

// The incident cell of a yarn-frame direction (upper hemisphere; one below
// counts by its polar angle's band, clamped).
size_t exitOffsetCell(const Vec3& wiLocal);
// The slot of an offset in a cell (kExitOffsetSlots - 1: beyond the axial
// range, or not finite).
size_t exitOffsetSlot(double dz, double dpsi);

}  // namespace weft
