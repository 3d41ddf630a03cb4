// weft/core/json_file.h — parsing a JSON input strictly, with a clear error.
//
// Every JSON input (scene.json, model.json, fiber parameters, the fit
// configuration, an RDM's meta.json) goes through parseJsonText, which is
// stricter than nlohmann::json::parse:
//   - a key that repeats in one object is an error (the default keeps the last);
//   - nesting deeper than kMaxJsonNesting levels is refused before any tree is
//     built (recursive code would otherwise walk a hostile depth);
//   - a number beyond double's range (1e400) is an error at its position;
// and every error is an InputError naming the source and the line:column
// ("model.json:3:14: malformed JSON: ...") or the JSON path of a duplicate key.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

namespace weft {

// A real input nests a handful of levels (a model's network layers: 4).
constexpr int kMaxJsonNesting = 64;

// `source` names the input in messages (a path, or "scene" for a document in memory).
nlohmann::json parseJsonText(std::string_view text, const std::string& source);

// readFile (core/file.h: regular files within the size limit) + parseJsonText.
nlohmann::json readJsonFile(const std::string& path);

}  // namespace weft
