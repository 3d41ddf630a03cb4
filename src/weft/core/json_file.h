// weft/core/json_file.h — reading a JSON input file with a clear error.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "weft/core/error.h"
#include "weft/core/file.h"

namespace weft {

// The parsed file; InputError naming `path` (and the byte offset of a syntax
// error) when it is missing, unreadable or malformed.
inline nlohmann::json readJsonFile(const std::string& path) {
    const std::string text = readFile(path);
    try {
        return nlohmann::json::parse(text);
    } catch (const nlohmann::json::parse_error& e) {
        throw InputError(path + ": malformed JSON at byte " + std::to_string(e.byte) + ": " + e.what());
    }
}

}  // namespace weft
