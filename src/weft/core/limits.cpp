#include "weft/core/limits.h"

#include <unistd.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

#include "weft/core/error.h"

namespace weft {

namespace {

constexpr uint64_t kDefaultMaxInputBytes = uint64_t{4} << 30;

// The variable's value, or `fallback` when it is unset or empty.
uint64_t sizeFromEnvironment(const char* name, uint64_t fallback) {
    const char* text = std::getenv(name);
    if (text == nullptr || *text == '\0') return fallback;
    return parseByteSize(text, name);
}

uint64_t physicalMemoryBytes() {
    const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGESIZE);
    if (pages <= 0 || pageSize <= 0) return uint64_t{8} << 30;  // unknown: assume 8 GiB
    return static_cast<uint64_t>(pages) * static_cast<uint64_t>(pageSize);
}

}  // namespace

uint64_t parseByteSize(const std::string& text, const std::string& name) {
    const auto fail = [&]() -> uint64_t {
        throw InputError(name + " = \"" + text +
                         "\": expected a byte count >= 1 with an optional K, M, G or T suffix "
                         "(e.g. 512M, 16G)");
    };
    size_t digits = 0;
    while (digits < text.size() && std::isdigit(static_cast<unsigned char>(text[digits]))) ++digits;
    if (digits == 0 || digits > 15) return fail();
    uint64_t value = std::stoull(text.substr(0, digits));
    const std::string suffix = text.substr(digits);
    int shift = 0;
    if (suffix.empty()) {
        shift = 0;
    } else if (suffix.size() == 1) {
        switch (std::toupper(static_cast<unsigned char>(suffix[0]))) {
            case 'K':
                shift = 10;
                break;
            case 'M':
                shift = 20;
                break;
            case 'G':
                shift = 30;
                break;
            case 'T':
                shift = 40;
                break;
            default:
                return fail();
        }
    } else {
        return fail();
    }
    if (value < 1 || value > (std::numeric_limits<uint64_t>::max() >> (shift + 1))) return fail();
    return value << shift;
}

uint64_t maxInputBytes() {
    return sizeFromEnvironment("WEFT_MAX_INPUT_BYTES", kDefaultMaxInputBytes);
}

uint64_t memoryBudgetBytes() {
    return sizeFromEnvironment("WEFT_MEMORY_BUDGET", physicalMemoryBytes() / 4 * 3);
}

std::string byteText(double bytes) {
    char text[64];
    if (!(bytes < 1e3)) {
        const char* units[] = {"KB", "MB", "GB", "TB", "PB", "EB"};
        int unit = 0;
        bytes /= 1e3;
        while (bytes >= 1e3 && unit < 5) bytes /= 1e3, ++unit;
        if (bytes >= 1e3)
            std::snprintf(text, sizeof text, "%.3g %s", bytes, units[unit]);
        else
            std::snprintf(text, sizeof text, "%.*f %s", bytes < 10 ? 1 : 0, bytes, units[unit]);
    } else {
        std::snprintf(text, sizeof text, "%.0f bytes", bytes);
    }
    return text;
}

void checkMemoryBudget(double bytes, const std::string& what) {
    const uint64_t budget = memoryBudgetBytes();
    if (!(bytes <= static_cast<double>(budget)))
        throw InputError(what + " needs about " + byteText(bytes) + ", over the memory budget of " +
                         byteText(static_cast<double>(budget)) +
                         " (set WEFT_MEMORY_BUDGET to change it; docs/limits.md)");
}

}  // namespace weft
