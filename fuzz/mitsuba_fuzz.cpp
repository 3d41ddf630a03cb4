// libFuzzer harness: Mitsuba 3 scene XML (render/mitsuba.h), imported as
// `weft scene import` does. The files it names resolve against the seeds'
// folder, which holds a curve file and a model, so that the curve shapes are
// read through; anything else must be an InputError.
#include "fuzz_util.h"
#include "weft/render/mitsuba.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    weft::fuzz::expectOnlyInputErrors([&] {
        weft::render::MitsubaImportOptions options;
        options.model = WEFT_SOURCE_DIR "/tests/data/fleece-small.json";
        weft::render::importMitsubaText(weft::fuzz::bytesOf(data, size), "fuzz.xml",
                                        WEFT_SOURCE_DIR "/fuzz/seeds/mitsuba", options);
    });
    return 0;
}
