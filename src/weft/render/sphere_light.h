// weft/render/sphere_light.h — a sphere of uniform emitted radiance, sampled
// uniformly in the cone of directions it subtends (pbrt-v3 Sphere::Sample(ref)),
// pdf 1 / (2 pi (1 - cos theta_max)); points inside the sphere get no samples
// (pdf 0). Scene type "sphere":
//   {"type": "sphere", "center": [x, y, z], "radius": r, "radiance": [r, g, b]}
// all required; coordinates within +-1e6, radius in [1e-6, 1e6], radiance in [0, 1e6].
#pragma once

#include "weft/render/light.h"

namespace weft::render {

class SphereLight final : public Light {
  public:
    // intersect() ignores hits at t <= kIntersectEpsilon (|org - center| +
    // radius), so that a ray leaving the sphere's surface does not hit it again.
    static constexpr double kIntersectEpsilon = 1e-9;

    // InputError unless center is finite, radius finite and > 0, radiance finite and >= 0.
    SphereLight(const Vec3& center, double radius, const Rgb& radiance);
    bool isInfinite() const override { return false; }
    LightSample sample(const Vec3& p, const std::array<double, 2>& u) const override;
    double pdf(const Vec3& p, const Vec3& wi) const override;
    Rgb radiance(const Vec3& d) const override;
    double intersect(const Vec3& org, const Vec3& dir, double tMax) const override;
    Rgb power(double) const override;

    const Vec3& center() const { return center_; }
    double radius() const { return radius_; }

  private:
    Vec3 center_;
    double radius_;
    Rgb radiance_;
};

struct SphereLightDesc final : LightDesc {
    Vec3 center;
    double radius = 0;
    Rgb radiance;

    SphereLightDesc(const Vec3& center, double radius, const Rgb& radiance)
        : center(center), radius(radius), radiance(radiance) {}
    const char* type() const override { return "sphere"; }
    nlohmann::json params() const override;
    std::unique_ptr<Light> create() const override;
};

// Its registration (light_types.cpp).
LightType sphereLightType();

}  // namespace weft::render
