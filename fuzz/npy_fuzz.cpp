// libFuzzer harness: the .npy reader (core/npy.h: RDMs, PAIRS arrays).
#include "fuzz_util.h"
#include "weft/core/npy.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    weft::fuzz::expectOnlyInputErrors(
        [&] { weft::decodeNpy(weft::fuzz::bytesOf(data, size), "fuzz.npy"); });
    return 0;
}
