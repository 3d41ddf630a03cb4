// Tests for weft/yarn/material_preset.h: the Table 3 presets are complete,
// valid, and looked up by name.
#include "weft/yarn/material_preset.h"

#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

#include "weft/core/error.h"
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

}  // namespace
}  // namespace weft
