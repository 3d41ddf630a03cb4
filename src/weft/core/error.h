// weft/core/error.h — the error types every stage throws.
//
// InputError: the user gave something invalid (a file, a field, a flag); the
// message names it and the allowed range, and the CLI exits with status 2.
// Any other std::exception is a bug or an environment failure (exit 1).
#pragma once

#include <stdexcept>
#include <string>

namespace weft {

class InputError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

}  // namespace weft
