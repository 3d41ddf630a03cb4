#include "weft/core/shard.h"

#include <charconv>

#include "weft/core/error.h"

namespace weft {

namespace {

// A whole decimal number, nothing else (no sign, no spaces).
bool parseCount(const std::string& text, int64_t& value) {
    if (text.empty() || text.size() > 18) return false;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    return ec == std::errc() && end == text.data() + text.size() && text[0] != '-' &&
           text[0] != '+';
}

}  // namespace

Shard Shard::parse(const std::string& text, const std::string& what) {
    const std::string form = " (expected K/N: shard K of N, 0 <= K < N <= " +
                             std::to_string(kMaxCount) + ", e.g. 0/4 ... 3/4)";
    const size_t slash = text.find('/');
    Shard s;
    if (slash == std::string::npos || !parseCount(text.substr(0, slash), s.index) ||
        !parseCount(text.substr(slash + 1), s.count))
        throw InputError(what + " \"" + text + "\" is not a shard" + form);
    if (s.count < 1 || s.count > kMaxCount || s.index >= s.count)
        throw InputError(what + " " + text + " is out of range" + form);
    return s;
}

std::string Shard::toString() const { return std::to_string(index) + "/" + std::to_string(count); }

void Shard::validate(int64_t total, const std::string& what, const std::string& items) const {
    if (count < 1 || count > kMaxCount || index < 0 || index >= count)
        throw InputError(what + " " + toString() + " is out of range: allowed 0 <= K < N <= " +
                         std::to_string(kMaxCount));
    if (count > total)
        throw InputError(what + " " + toString() + ": " + std::to_string(count) +
                         " shards of " + std::to_string(total) + " " + items +
                         " would leave some empty: allowed N <= " + std::to_string(total));
}

}  // namespace weft
