#include "weft/render/delta_lights.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "weft/core/error.h"
#include "weft/core/json_message.h"
#include "weft/core/math.h"
#include "weft/render/scene_reader.h"

namespace weft::render {

// ---------------------------------------------------------------------------
// PointLight

PointLight::PointLight(const Vec3& position, const Rgb& intensity)
    : position_(position), intensity_(intensity) {
    if (!isFinite(position))
        throw InputError("point light: position " + streamedText(position) + " must be finite");
    checkLightRadiance(intensity, "point light");
}

LightSample PointLight::sample(const Vec3& p, const std::array<double, 2>&) const {
    const Vec3 toLight = position_ - p;
    const double distance2 = dot(toLight, toLight);
    if (!(distance2 > 0) || !std::isfinite(distance2)) return {};
    const double distance = std::sqrt(distance2);
    return {toLight / distance, intensity_ / distance2, 1.0, distance};
}

Rgb PointLight::power(double) const { return intensity_ * (4.0 * kPi); }

// ---------------------------------------------------------------------------
// DirectionalLight

DirectionalLight::DirectionalLight(const Vec3& direction, const Rgb& irradiance)
    : irradiance_(irradiance) {
    // Scaled by its largest component first, so that tiny and huge
    // directions normalize without underflow or overflow.
    const double largest =
        std::max({std::abs(direction.x), std::abs(direction.y), std::abs(direction.z)});
    if (!isFinite(direction) || !(largest > 0))
        throw InputError("directional light: direction " + streamedText(direction) +
                         " must be finite and not 0");
    towardsLight_ = -normalize(direction / largest);
    checkLightRadiance(irradiance, "directional light");
}

LightSample DirectionalLight::sample(const Vec3&, const std::array<double, 2>&) const {
    return {towardsLight_, irradiance_, 1.0, std::numeric_limits<double>::infinity()};
}

Rgb DirectionalLight::power(double sceneRadius) const {
    return irradiance_ * (kPi * sceneRadius * sceneRadius);
}

// ---------------------------------------------------------------------------
// The scene types

nlohmann::json PointLightDesc::params() const {
    return {{"position", vecJson(position)}, {"intensity", rgbJson(intensity)}};
}

std::unique_ptr<Light> PointLightDesc::create() const {
    return std::make_unique<PointLight>(position, intensity);
}

LightType pointLightType() {
    return {"point", [](JsonObjectReader& r, const std::string&) {
                r.allowKeys({"type", "position", "intensity"});
                const Vec3 position = readSceneVec3(r, "position");
                return std::shared_ptr<const LightDesc>(
                    std::make_shared<PointLightDesc>(position, readRadiance(r, "intensity")));
            }};
}

nlohmann::json DirectionalLightDesc::params() const {
    return {{"direction", vecJson(direction)}, {"irradiance", rgbJson(irradiance)}};
}

std::unique_ptr<Light> DirectionalLightDesc::create() const {
    return std::make_unique<DirectionalLight>(direction, irradiance);
}

LightType directionalLightType() {
    return {"directional", [](JsonObjectReader& r, const std::string&) {
                r.allowKeys({"type", "direction", "irradiance"});
                const Vec3 direction = readSceneVec3(r, "direction");
                if (direction.x == 0 && direction.y == 0 && direction.z == 0)
                    r.fail("direction", "the direction the light travels cannot be 0");
                return std::shared_ptr<const LightDesc>(std::make_shared<DirectionalLightDesc>(
                    direction, readRadiance(r, "irradiance")));
            }};
}

}  // namespace weft::render
