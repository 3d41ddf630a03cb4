// The registry of yarn drawing modes (yarn_mode.h): one line per mode.
#include "weft/core/error.h"
#include "weft/render/yarn_mode.h"

namespace weft::render {

// Each defined in its own file.
const YarnMode& neuralYarnMode();  // neural_mode.cpp
const YarnMode& fiberYarnMode();   // fiber_mode.cpp
const YarnMode& dualYarnMode();    // dual_mode.cpp

const std::vector<const YarnMode*>& yarnModes() {
    static const std::vector<const YarnMode*> modes = {
        &neuralYarnMode(),
        &fiberYarnMode(),
        &dualYarnMode(),
    };
    return modes;
}

const YarnMode& defaultYarnMode() { return neuralYarnMode(); }

const YarnMode& yarnModeNamed(const std::string& name, const std::string& field) {
    std::string allowed;
    for (const YarnMode* mode : yarnModes()) {
        if (name == mode->name()) return *mode;
        allowed += (allowed.empty() ? "" : ", ") + std::string(mode->name());
    }
    throw InputError(field + " \"" + name + "\" is not a render mode: allowed " + allowed);
}

std::string readYarnModeName(const JsonObjectReader& r, std::string_view key) {
    std::vector<std::string_view> names;
    for (const YarnMode* mode : yarnModes()) names.push_back(mode->name());
    return std::string(names[r.oneOf(key, names)]);
}

}  // namespace weft::render
