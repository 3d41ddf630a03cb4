// weft/core/limits.h — the documented bounds on what one weft job reads and
// allocates (docs/limits.md), so that a hostile or mistaken input gets a clear
// error up front instead of running the machine out of memory.
//
//   - Input files: regular files only, at most maxInputBytes() each (default
//     4 GiB; environment variable WEFT_MAX_INPUT_BYTES).
//   - Planned allocations (a ply's fibers, an RDM's bins, a film, a decoded
//     image, curve geometry): estimated before they are made and refused above
//     memoryBudgetBytes() (default 3/4 of the machine's physical memory;
//     environment variable WEFT_MEMORY_BUDGET).
// Both variables take a byte count with an optional K, M, G or T suffix
// (powers of 1024): "512M", "16G". A malformed value is an InputError naming
// the variable.
#pragma once

#include <cstdint>
#include <string>

namespace weft {

uint64_t maxInputBytes();
uint64_t memoryBudgetBytes();

// Throws InputError "<what> needs about 7.2 GB, over the memory budget of
// 6 GB (WEFT_MEMORY_BUDGET)" when `bytes` exceeds the budget. `bytes` is a
// double so that an estimate cannot overflow on the way here.
void checkMemoryBudget(double bytes, const std::string& what);

// "7.2 GB", "850 MB", "12 KB", "80 bytes" (powers of 1000, as people read them).
std::string byteText(double bytes);

// Parses a size such as "512M" (K, M, G, T: powers of 1024); InputError naming
// `name` otherwise. Exposed for tests.
uint64_t parseByteSize(const std::string& text, const std::string& name);

}  // namespace weft
