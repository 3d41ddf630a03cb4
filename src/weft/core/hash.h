// weft/core/hash.h — FNV-1a, the 64-bit hash of scene files and their
// inputs (render/scene_file.h) and of a render part's pixels (pixelChecksum,
// core/image.h). Not cryptographic: it tells damaged or mixed-up data from the
// data it was computed on.
#pragma once

#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

namespace weft {

inline constexpr uint64_t kFnv1a64Offset = 0xcbf29ce484222325ULL;

// FNV-1a, 64 bit, of `bytes`, continuing from `hash` (kFnv1a64Offset starts
// a new one), so that a hash can be taken piece by piece.
inline uint64_t fnv1a64(std::string_view bytes, uint64_t hash = kFnv1a64Offset) {
    for (const char c : bytes) {
        hash ^= static_cast<unsigned char>(c);
        hash *= 0x100000001b3ULL;
    }
    return hash;
}

// Sixteen lower-case hex digits.
inline std::string hex16(uint64_t v) {
    char buffer[17];
    std::snprintf(buffer, sizeof buffer, "%016" PRIx64, v);
    return buffer;
}

}  // namespace weft
