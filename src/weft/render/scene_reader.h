// weft/render/scene_reader.h — the scene file's value kinds (docs/scene-format.md),
// shared by the scene reader and the readers of its registered entries (a
// light type, light.h; a yarn drawing mode, yarn_mode.h). Each reads through
// the strict JSON reader (core/json_reader.h), so every error names the scene
// file, the JSON path and the allowed range.
#pragma once

#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "weft/core/json_reader.h"
#include "weft/core/rgb.h"
#include "weft/core/vec.h"
#include "weft/render/scene_limits.h"

namespace weft::render {

// Lengths and scales: Embree works in float, so a scene is kept within
// kMaxSceneCoordinate and its lengths within a factor 1e12 of each other.
NumberRange sceneLengthRange();

// A point or vector, each coordinate within kMaxSceneCoordinate.
Vec3 readSceneVec3(const JsonObjectReader& r, std::string_view key);
// Linear RGB radiance, each channel in [0, kMaxRadiance].
Rgb readRadiance(const JsonObjectReader& r, std::string_view key);
// A file name, resolved against baseDir unless absolute; `extensions`
// (lowercase, with the dot) lists the accepted ones, empty: any. The file is
// not opened.
std::string readFileName(const JsonObjectReader& r, std::string_view key,
                         const std::string& baseDir,
                         std::initializer_list<const char*> extensions);

// [x, y, z] as the scene file writes it.
nlohmann::json vecJson(const Vec3& v);

}  // namespace weft::render
