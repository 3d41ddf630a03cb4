// weft/core/error.h — the error types every stage throws.
//
// InputError: the user gave something invalid (a file, a field, a flag); the
// message names it and the allowed range, and the CLI exits with status 2.
// Any other std::exception is a bug or an environment failure (exit 1).
// checkRange is the one wording of an integer out of its range.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace weft {

class InputError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

// InputError "<label> <value> is out of range: allowed [lo, hi]<note>" unless
// lo <= value <= hi. The label names the quantity as the user gave it, with
// its separator: "threads =" for an options field, "--threads" for a flag.
inline void checkRange(const std::string& label, int64_t value, int64_t lo, int64_t hi,
                       const std::string& note = "") {
    if (value < lo || value > hi)
        throw InputError(label + " " + std::to_string(value) + " is out of range: allowed [" +
                         std::to_string(lo) + ", " + std::to_string(hi) + "]" + note);
}

}  // namespace weft
