// weft/render/scene_limits.h — the numeric bounds of a scene (docs/limits.md).
//
// Embree works in float and the path tracer multiplies radiance by path
// weights, so coordinates (camera, lights, curve points times their scale)
// stay within +-kMaxSceneCoordinate, lengths (radii, scales) within
// [kMinSceneLength, kMaxSceneCoordinate], and radiance (light radiance,
// light scales, an envmap's texels times its scale) within [0, kMaxRadiance].
#pragma once

namespace weft::render {

inline constexpr double kMaxSceneCoordinate = 1e6;
inline constexpr double kMinSceneLength = 1e-6;
inline constexpr double kMaxRadiance = 1e6;

}  // namespace weft::render
