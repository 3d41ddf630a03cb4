// weft/core/json_message.h — pieces of error messages about JSON input.
//
// Used by the strict reader (json_reader.h) and by the shape checks that the
// readers of model.json and scene.json keep beside it, so that all name values
// and keys the same way:
//   `yarns[1].plies = 0 is out of range`, `got the string "x"`, `got an array of 2`.
#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "weft/core/rgb.h"

namespace weft {

// Shortest round-trip decimal form ("0.1", "nan", "inf").
std::string formatNumber(double v);
// A string as a JSON literal (escaped, invalid UTF-8 replaced), cut to 60 bytes.
std::string jsonString(std::string_view s);
// "null", "true", "the string \"x\"", "an array of 2", "an object", "3", "0.5".
std::string describeJson(const nlohmann::json& v);
// "camera" + "fov_deg" -> "camera.fov_deg" ("" + key -> key).
std::string jsonChildPath(const std::string& path, std::string_view key);
// "yarns" + 1 -> "yarns[1]".
std::string jsonIndexPath(const std::string& path, size_t index);

// [r, g, b]: the one JSON form of a colour in reports and files.
nlohmann::json rgbJson(const Rgb& c);

}  // namespace weft
