// libFuzzer harness: model.json text (yarn/yarn_model.h) and, when it loads,
// the checks the runtime BSDF adds (finite networks over their domain).
#include "fuzz_util.h"
#include "weft/core/json_file.h"
#include "weft/fiber/fiber_params.h"
#include "weft/yarn/yarn_model.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    weft::fuzz::expectOnlyInputErrors([&] {
        const nlohmann::json j = weft::parseJsonText(weft::fuzz::bytesOf(data, size), "model.json");
        // The same document as fiber parameters (--params FILE.json) too.
        weft::fuzz::expectOnlyInputErrors(
            [&] { weft::FiberParams::fromJson(j, "params.json").validate("params.json"); });
        const weft::YarnModel model = weft::yarnModelFromJson(j, "model.json");
        model.tNet.checkFiniteOnUnitInputs("t_net");
        model.mNet.checkFiniteOnUnitInputs("m_net");
    });
    return 0;
}
