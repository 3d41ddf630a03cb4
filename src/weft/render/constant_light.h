// weft/render/constant_light.h — radiance L from every direction, sampled
// uniformly over the sphere (pdf 1 / 4 pi). Scene type "constant":
//   {"type": "constant", "radiance": [r, g, b]}   (required; each in [0, 1e6])
#pragma once

#include "weft/render/light.h"

namespace weft::render {

class ConstantLight final : public Light {
  public:
    // InputError unless every channel is finite and >= 0.
    explicit ConstantLight(const Rgb& radiance);
    bool isInfinite() const override { return true; }
    LightSample sample(const Vec3& p, const std::array<double, 2>& u) const override;
    double pdf(const Vec3& p, const Vec3& wi) const override;
    Rgb radiance(const Vec3& d) const override;
    double intersect(const Vec3&, const Vec3&, double) const override { return -1.0; }
    Rgb power(double sceneRadius) const override;

  private:
    Rgb radiance_;
};

struct ConstantLightDesc final : LightDesc {
    Rgb radiance;

    explicit ConstantLightDesc(const Rgb& radiance) : radiance(radiance) {}
    const char* type() const override { return "constant"; }
    nlohmann::json params() const override;
    std::unique_ptr<Light> create() const override;
};

// Its registration (light_types.cpp).
LightType constantLightType();

}  // namespace weft::render
