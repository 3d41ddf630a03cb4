// libFuzzer harness: scene.json text (render/scene_file.h), parsed and
// validated as `weft render` does before it reads any referenced file.
#include "fuzz_util.h"
#include "weft/render/scene_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    weft::fuzz::expectOnlyInputErrors([&] {
        weft::render::parseSceneText(weft::fuzz::bytesOf(data, size), "fuzz.json", "/nonexistent");
    });
    return 0;
}
