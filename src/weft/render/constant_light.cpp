#include "weft/render/constant_light.h"

#include <limits>

#include "weft/core/json_message.h"
#include "weft/core/math.h"
#include "weft/core/sampling.h"
#include "weft/render/scene_reader.h"

namespace weft::render {

ConstantLight::ConstantLight(const Rgb& radiance) : radiance_(radiance) {
    checkLightRadiance(radiance, "constant light");
}

LightSample ConstantLight::sample(const Vec3&, const std::array<double, 2>& u) const {
    return {sampleUniformSphere(u[0], u[1]), radiance_, uniformSpherePdf(),
            std::numeric_limits<double>::infinity()};
}

double ConstantLight::pdf(const Vec3&, const Vec3&) const { return uniformSpherePdf(); }

Rgb ConstantLight::radiance(const Vec3&) const { return radiance_; }

nlohmann::json ConstantLightDesc::params() const { return {{"radiance", rgbJson(radiance)}}; }

std::unique_ptr<Light> ConstantLightDesc::create() const {
    return std::make_unique<ConstantLight>(radiance);
}

LightType constantLightType() {
    return {"constant", [](JsonObjectReader& r, const std::string&) {
                r.allowKeys({"type", "radiance"});
                return std::shared_ptr<const LightDesc>(
                    std::make_shared<ConstantLightDesc>(readRadiance(r, "radiance")));
            }};
}

Rgb ConstantLight::power(double sceneRadius) const {
    return radiance_ * (4.0 * kPi * kPi * sceneRadius * sceneRadius);
}

}  // namespace weft::render
