#include "weft/render/light.h"

#include <sstream>

#include "weft/core/error.h"

namespace weft::render {

void checkLightRadiance(const Rgb& radiance, std::string_view light) {
    if (radiance.isFinite() && radiance.r >= 0 && radiance.g >= 0 && radiance.b >= 0) return;
    std::ostringstream message;
    message << light << ": radiance " << radiance << " must be finite and >= 0 in every channel";
    throw InputError(message.str());
}

std::shared_ptr<const LightDesc> readLight(JsonObjectReader r, const std::string& baseDir) {
    const std::vector<LightType>& types = lightTypes();
    std::vector<std::string_view> names;
    for (const LightType& t : types) names.push_back(t.name);
    // The type decides the other keys: it is read before they are checked.
    return types[r.oneOf("type", names)].read(r, baseDir);
}

nlohmann::json toJson(const LightDesc& light) {
    nlohmann::json j = light.params();
    j["type"] = light.type();
    return j;
}

}  // namespace weft::render
