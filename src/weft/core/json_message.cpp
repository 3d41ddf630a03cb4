#include "weft/core/json_message.h"

#include <charconv>
#include <cstdint>

namespace weft {

namespace {
constexpr size_t kMaxQuoted = 60;
}  // namespace

std::string formatNumber(double v) {
    char buffer[64];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, v);
    return std::string(buffer, result.ptr);
}

std::string jsonString(std::string_view s) {
    const bool cut = s.size() > kMaxQuoted;
    const nlohmann::json literal = std::string(s.substr(0, cut ? kMaxQuoted : s.size()));
    std::string out = literal.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    if (cut) out.insert(out.size() - 1, "...");
    return out;
}

std::string describeJson(const nlohmann::json& v) {
    using value_t = nlohmann::json::value_t;
    switch (v.type()) {
        case value_t::null:
            return "null";
        case value_t::boolean:
            return v.get<bool>() ? "true" : "false";
        case value_t::string:
            return "the string " + jsonString(v.get_ref<const std::string&>());
        case value_t::array:
            return "an array of " + std::to_string(v.size());
        case value_t::object:
            return "an object";
        case value_t::number_integer:
            return std::to_string(v.get<int64_t>());
        case value_t::number_unsigned:
            return std::to_string(v.get<uint64_t>());
        case value_t::number_float:
            return formatNumber(v.get<double>());
        default:
            return "an unsupported value";
    }
}

std::string jsonChildPath(const std::string& path, std::string_view key) {
    return path.empty() ? std::string(key) : path + "." + std::string(key);
}

std::string jsonIndexPath(const std::string& path, size_t index) {
    return path + "[" + std::to_string(index) + "]";
}

nlohmann::json rgbJson(const Rgb& c) { return nlohmann::json::array({c.r, c.g, c.b}); }

}  // namespace weft
