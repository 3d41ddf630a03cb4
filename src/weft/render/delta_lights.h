// weft/render/delta_lights.h — lights without extent, reached only by
// next-event estimation (Light::isDelta): no ray hits them, and BSDF
// sampling never finds them (pbrt-v4 PointLight and DistantLight; Mitsuba 3
// "point" and "directional").
//
// Scene type "point": radiant intensity I (W/sr) from one position; the
// radiance a point p receives is I / |position - p|^2 along the direction
// to the light.
//   {"type": "point", "position": [x, y, z], "intensity": [r, g, b]}
// Scene type "directional": irradiance E (W/m^2, on a surface facing the
// light) arriving along one direction from infinitely far (a sun).
//   {"type": "directional", "direction": [x, y, z], "irradiance": [r, g, b]}
// "direction" is the way the light travels (Mitsuba's convention), any
// length but 0. All keys required; coordinates within +-1e6, intensity and
// irradiance in [0, 1e6] per channel.
#pragma once

#include "weft/render/light.h"

namespace weft::render {

class PointLight final : public Light {
  public:
    // InputError unless position is finite and intensity finite and >= 0.
    PointLight(const Vec3& position, const Rgb& intensity);
    bool isInfinite() const override { return false; }
    bool isDelta() const override { return true; }
    // wi towards the position, radiance I / d^2, pdf 1 (a probability), the
    // distance d; no sample at the position itself.
    LightSample sample(const Vec3& p, const std::array<double, 2>& u) const override;
    double pdf(const Vec3&, const Vec3&) const override { return 0; }
    Rgb radiance(const Vec3&) const override { return intensity_; }
    double intersect(const Vec3&, const Vec3&, double) const override { return -1.0; }
    // 4 pi I.
    Rgb power(double) const override;

  private:
    Vec3 position_;
    Rgb intensity_;
};

class DirectionalLight final : public Light {
  public:
    // InputError unless direction is finite and not 0, irradiance finite and >= 0.
    DirectionalLight(const Vec3& direction, const Rgb& irradiance);
    bool isInfinite() const override { return true; }
    bool isDelta() const override { return true; }
    // wi = -direction, radiance E, pdf 1, distance +infinity.
    LightSample sample(const Vec3& p, const std::array<double, 2>& u) const override;
    double pdf(const Vec3&, const Vec3&) const override { return 0; }
    Rgb radiance(const Vec3&) const override { return irradiance_; }
    double intersect(const Vec3&, const Vec3&, double) const override { return -1.0; }
    // pi R^2 E: what crosses the scene's disc facing the light.
    Rgb power(double sceneRadius) const override;

  private:
    Vec3 towardsLight_;
    Rgb irradiance_;
};

struct PointLightDesc final : LightDesc {
    Vec3 position;
    Rgb intensity;

    PointLightDesc(const Vec3& position, const Rgb& intensity)
        : position(position), intensity(intensity) {}
    const char* type() const override { return "point"; }
    nlohmann::json params() const override;
    std::unique_ptr<Light> create() const override;
};

struct DirectionalLightDesc final : LightDesc {
    Vec3 direction;  // as written (not normalized), so that the scene writes it back unchanged
    Rgb irradiance;

    DirectionalLightDesc(const Vec3& direction, const Rgb& irradiance)
        : direction(direction), irradiance(irradiance) {}
    const char* type() const override { return "directional"; }
    nlohmann::json params() const override;
    std::unique_ptr<Light> create() const override;
};

// Their registrations (light_types.cpp).
LightType pointLightType();
LightType directionalLightType();

}  // namespace weft::render
