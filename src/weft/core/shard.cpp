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

void checkCompleteShardSet(const std::vector<Shard>& shards,
                           const std::vector<std::string>& names) {
    if (shards.empty()) throw InputError("no parts to merge");
    const int64_t n = shards[0].count;
    std::vector<int64_t> owner(static_cast<size_t>(n), -1);
    for (size_t k = 0; k < shards.size(); ++k) {
        if (shards[k].count != n || shards[k].index < 0 || shards[k].index >= n)
            throw InputError(names[k] + " is shard " + shards[k].toString() + ", but " + names[0] +
                             " is shard " + shards[0].toString() + ": the parts are of different jobs");
        int64_t& o = owner[static_cast<size_t>(shards[k].index)];
        if (o >= 0)
            throw InputError(names[k] + " and " + names[static_cast<size_t>(o)] +
                             " are both shard " + shards[k].toString() + ": give each shard once");
        o = static_cast<int64_t>(k);
    }
    std::string missing;
    int64_t missingCount = 0;
    for (int64_t i = 0; i < n; ++i)
        if (owner[static_cast<size_t>(i)] < 0 && missingCount++ < 8)
            missing += (missing.empty() ? "" : ", ") + Shard{i, n}.toString();
    if (missingCount > 0)
        throw InputError(std::to_string(missingCount) + " of the " + std::to_string(n) +
                         " shards missing (" + missing + (missingCount > 8 ? ", ..." : "") +
                         "): give all " + std::to_string(n) + " parts");
}

}  // namespace weft
