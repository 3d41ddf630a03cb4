// libFuzzer harness: model.json text (yarn/yarn_model.h) and, when it loads,
// the checks the runtime BSDF adds (finite networks over their domain); the
// same document as a family model (yarn/family_model.h: its reader, and the
// yarn at the box's centre and at a preset), a family box (BOX.json) and a
// family yarn (a scene's "yarn").
#include "fuzz_util.h"
#include "weft/core/json_file.h"
#include "weft/fiber/fiber_params.h"
#include "weft/yarn/family_model.h"
#include "weft/yarn/material_preset.h"
#include "weft/yarn/yarn_model.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    weft::fuzz::expectOnlyInputErrors([&] {
        const nlohmann::json j = weft::parseJsonText(weft::fuzz::bytesOf(data, size), "model.json");
        // The same document as fiber parameters (--params FILE.json) too.
        weft::fuzz::expectOnlyInputErrors(
            [&] { weft::FiberParams::fromJson(j, "params.json").validate("params.json"); });
        weft::fuzz::expectOnlyInputErrors([&] {
            const weft::FamilyModel family = weft::familyModelFromJson(j, "family.json");
            family.at(family.centre(), "centre");
            family.at(weft::yarnPointOf(weft::findMaterialPreset("fleece")), "fleece");
        });
        weft::fuzz::expectOnlyInputErrors([&] { weft::FamilyBox::fromJson(j, "box.json"); });
        weft::fuzz::expectOnlyInputErrors([&] { weft::YarnPoint::fromJson(j, "yarn", ""); });
        const weft::YarnModel model = weft::yarnModelFromJson(j, "model.json");
        model.tNet.checkFiniteOnUnitInputs("t_net");
        model.mNet.checkFiniteOnUnitInputs("m_net");
    });
    return 0;
}
