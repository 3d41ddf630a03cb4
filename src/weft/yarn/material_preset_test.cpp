// Tests for weft/yarn/material_preset.h: the Table 3 presets are complete,
// valid, and looked up by name.
#include "weft/yarn/material_preset.h"

#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/family_box.h"
#include "weft/core/test_util.h"

namespace weft {
namespace {

TEST(MaterialPreset, TheFiveTable3MaterialsInOrder) {
    std::vector<std::string> names;
    for (const MaterialPreset& p : materialPresets()) names.emplace_back(p.name);
    EXPECT_EQ(names,
              (std::vector<std::string>{"fleece", "silk", "polyester", "cotton", "gabardine"}));
}

TEST(MaterialPreset, EveryPresetIsValid) {
    for (const MaterialPreset& p : materialPresets()) {
        EXPECT_NO_THROW(p.fiber.validate("preset " + std::string(p.name)));
        EXPECT_NO_THROW(p.ply.validate()) << p.name;
    }
}

TEST(MaterialPreset, FindReturnsThePresetOrListsTheNames) {
    for (const MaterialPreset& p : materialPresets()) EXPECT_EQ(&findMaterialPreset(p.name), &p);
    EXPECT_EQ(findMaterialPreset("cotton").ply.fibers, 600);
    EXPECT_EQ(findMaterialPreset("silk").fiber.betaRDeg, 1.0);
    testing::expectInputError(
        [] { findMaterialPreset("wool"); },
        {"unknown preset \"wool\"", "(allowed: fleece, silk, polyester, cotton, gabardine)"});
    EXPECT_THROW(findMaterialPreset("Fleece"), InputError);  // names are case-sensitive
}

// The family box of issue 42 (docs/family.md) holds the five materials of the paper.
TEST(MaterialPreset, TheDefaultFamilyBoxHoldsEveryPreset) {
    const FamilyBox box;
    for (const MaterialPreset& preset : materialPresets()) {
        const YarnPoint p{preset.ply.fibers,     preset.ply.density,     preset.ply.twist,
                          preset.fiber.betaRDeg, preset.fiber.betaTTDeg, preset.fiber.gammaTTDeg,
                          preset.fiber.cR};
        EXPECT_NO_THROW(box.check(p, std::string(preset.name))) << preset.name;
    }
}

}  // namespace
}  // namespace weft
