// libFuzzer harness: the image readers of core/image_io.h. The first byte
// picks OpenEXR or Radiance HDR (envmaps, `weft compare`) or PNG (`weft
// montage`, `weft compare`).
#include "fuzz_util.h"
#include "weft/core/image_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size == 0) return 0;
    const std::string bytes = weft::fuzz::bytesOf(data + 1, size - 1);
    weft::fuzz::expectOnlyInputErrors([&] {
        switch (data[0] % 3) {
            case 0:
                weft::decodeImage(bytes, "fuzz.exr");
                break;
            case 1:
                weft::decodeImage(bytes, "fuzz.hdr");
                break;
            default:
                weft::decodePng(bytes, "fuzz.png");
                break;
        }
    });
    return 0;
}
