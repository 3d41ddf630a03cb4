#include "weft/render/scene_reader.h"

#include <algorithm>
#include <filesystem>
#include <vector>

#include "weft/core/file.h"
#include "weft/core/json_message.h"

namespace weft::render {

namespace {

std::string joinNames(std::initializer_list<const char*> names) {
    std::string out;
    for (const char* n : names) out += (out.empty() ? "" : ", ") + std::string(n);
    return out;
}

}  // namespace

NumberRange sceneLengthRange() {
    return NumberRange::closed(kMinSceneLength, kMaxSceneCoordinate).with("scene units");
}

Vec3 readSceneVec3(const JsonObjectReader& r, std::string_view key) {
    const std::vector<double> v = r.numbers(
        key, 3, NumberRange::closed(-kMaxSceneCoordinate, kMaxSceneCoordinate).with("scene units"));
    return {v[0], v[1], v[2]};
}

Rgb readRadiance(const JsonObjectReader& r, std::string_view key) {
    const std::vector<double> v =
        r.numbers(key, 3, NumberRange::closed(0, kMaxRadiance), "(r, g, b)");
    return {v[0], v[1], v[2]};
}

std::string readFileName(const JsonObjectReader& r, std::string_view key,
                         const std::string& baseDir,
                         std::initializer_list<const char*> extensions) {
    const nlohmann::json& v = r.value(key);
    if (!v.is_string()) r.fail(key, "expected a file name, got " + describeJson(v));
    const std::string& name = v.get_ref<const std::string&>();
    if (name.empty()) r.fail(key, "expected a file name, got the empty string");
    // The C library would stop at the NUL and open some other file.
    if (name.find('\0') != std::string::npos)
        r.fail(key, "a file name cannot contain a NUL character");
    if (extensions.size() != 0) {
        const std::string ext = lowercaseExtension(name);
        if (std::none_of(extensions.begin(), extensions.end(),
                         [&](const char* e) { return ext == e; }))
            r.fail(key, jsonString(name) + " has an unsupported extension (allowed: " +
                            joinNames(extensions) + ")");
    }
    return (std::filesystem::path(baseDir) / name).string();
}

nlohmann::json vecJson(const Vec3& v) { return nlohmann::json::array({v.x, v.y, v.z}); }

}  // namespace weft::render
