// fuzz/fuzz_util.h — what every harness shares: a bad input must end in
// weft::InputError. Any other exception escapes LLVMFuzzerTestOneInput and
// libFuzzer reports it (as it does a crash, a sanitizer finding, a hang or an
// allocation over -rss_limit_mb).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "weft/core/error.h"

namespace weft::fuzz {

// The input as bytes (harnesses that pick a reader by the first byte pass
// the rest).
inline std::string bytesOf(const uint8_t* data, size_t size) {
    return std::string(reinterpret_cast<const char*>(data), size);
}

// Runs f(); an InputError is the expected answer to a bad input.
template <typename F>
void expectOnlyInputErrors(F&& f) {
    try {
        f();
    } catch (const InputError&) {
    }
}

}  // namespace weft::fuzz
