// The registry of light types (light.h): one line per type, in the order
// docs/scene-format.md lists them (and the scene reader's messages name them).
#include "weft/render/constant_light.h"
#include "weft/render/delta_lights.h"
#include "weft/render/environment_light.h"
#include "weft/render/light.h"
#include "weft/render/sphere_light.h"

namespace weft::render {

const std::vector<LightType>& lightTypes() {
    static const std::vector<LightType> types = {
        skyLightType(),      envmapLightType(), sphereLightType(),
        constantLightType(), pointLightType(),  directionalLightType(),
    };
    return types;
}

}  // namespace weft::render
