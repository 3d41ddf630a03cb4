#include "weft/render/light.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "weft/core/error.h"
#include "weft/core/math.h"

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

Rgb averageRadiance(const Light& infinite) {
    // Cells of equal solid angle: uniform in phi and in cos theta.
    constexpr int kPhi = 256, kCos = 128;
    Rgb sum(0.0);
    for (int j = 0; j < kCos; ++j) {
        const double z = 1.0 - 2.0 * (j + 0.5) / kCos;
        const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
        for (int i = 0; i < kPhi; ++i) {
            const double phi = kTwoPi * (i + 0.5) / kPhi;
            sum += infinite.radiance(Vec3(s * std::cos(phi), s * std::sin(phi), z));
        }
    }
    return sum / static_cast<double>(kPhi * kCos);
}

}  // namespace weft::render
