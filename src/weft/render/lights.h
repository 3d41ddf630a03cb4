// weft/render/lights.h — the light sources of a cloth scene (issue 7, docs/design.md 8).
//
// Four kinds, all behind one interface so that the path tracer can do
// next-event estimation (sample) and multiple importance sampling (pdf) the
// same way for each:
//   ConstantLight     radiance L from every direction; uniform sphere sampling
//                     (pdf 1 / 4 pi).
//   EnvironmentLight  a lat-long RGB image (OpenEXR or Radiance .hdr) times
//                     `scale`, rotated by `rotate_deg` about +y; importance
//                     sampled with a piecewise-constant 2D distribution over
//                     the texels (luminance times sin theta of the row), whose
//                     density is exactly what pdf() returns. Radiance is
//                     piecewise constant (nearest texel), so sampling and
//                     lookup agree.
//   The procedural sky (skyLight()) is an EnvironmentLight over an image
//                     computed from a documented analytic formula (docs/scene-format.md,
//                     "Procedural sky"; see skyRadiance below). It is importance
//                     sampled by that image's texels like any map, but its
//                     radiance is the formula itself at the exact direction, so
//                     it is smooth (a nearest-texel lookup shows bands) and the
//                     pdf stays exactly what sample() draws from.
//   SphereLight       a sphere of uniform emitted radiance; sampled uniformly
//                     in the cone of directions it subtends (pbrt-v3
//                     Sphere::Sample(ref)), pdf 1 / (2 pi (1 - cos theta_max));
//                     points inside the sphere get no samples (pdf 0).
//
// Lat-long convention (Mitsuba 3's envmap, world +y up): a unit direction d
// (pointing away from the scene, towards the light) has, before the rotation,
//   u = (atan2(d.x, -d.z) / (2 pi)) mod 1      column: x = u * width
//   v = acos(d.y) / pi                          row:    y = v * height (row 0 at the top, +y)
// so texel (x, y) covers phi in [2 pi x / W, 2 pi (x + 1) / W), theta in
// [pi y / H, pi (y + 1) / H). rotate_deg turns the map about +y: the
// direction d sees the unrotated map at R_y(-rotate_deg) d, where
//   R_y(a) (x, y, z) = (x cos a + z sin a, y, -x sin a + z cos a)
// (right-handed: a = 90 degrees turns +z into +x, so rotate_deg = 90 shows
// the centre column of the image, unrotated at +z, at +x).
//
// All directions are world-space unit vectors; LightSample::wi points from
// the shading point towards the light.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "weft/core/image.h"
#include "weft/core/rgb.h"
#include "weft/core/vec.h"

namespace weft::render {

struct LightSample {
    Vec3 wi;              // unit direction from the shading point to the light
    Rgb radiance;         // emitted radiance arriving along -wi (not divided by pdf)
    double pdf = 0;       // solid-angle density of wi at the shading point; 0: no sample
    double distance = 0;  // to the light's surface; +infinity for infinite lights

    bool valid() const { return pdf > 0; }
};

class Light {
  public:
    virtual ~Light() = default;

    // Infinite lights (constant, envmap, sky) are seen by rays that escape the
    // scene; finite ones (spheres) by rays that hit them.
    virtual bool isInfinite() const = 0;
    // A direction towards the light from point p, with u uniform in [0, 1)^2.
    virtual LightSample sample(const Vec3& p, const std::array<double, 2>& u) const = 0;
    // Solid-angle density with which sample(p, .) returns wi (0 if it never does).
    virtual double pdf(const Vec3& p, const Vec3& wi) const = 0;
    // Infinite lights: radiance arriving from direction d (unit, pointing
    // away from the scene). Finite lights: the radiance of their surface
    // (the same everywhere).
    virtual Rgb radiance(const Vec3& d) const = 0;
    // For finite lights: distance along the ray (org, unit dir) to the first
    // intersection with the light's surface in (0, tMax), or a negative
    // value. Infinite lights return a negative value.
    virtual double intersect(const Vec3& org, const Vec3& dir, double tMax) const = 0;
};

class ConstantLight final : public Light {
  public:
    // InputError unless every channel is finite and >= 0.
    explicit ConstantLight(const Rgb& radiance);
    bool isInfinite() const override { return true; }
    LightSample sample(const Vec3& p, const std::array<double, 2>& u) const override;
    double pdf(const Vec3& p, const Vec3& wi) const override;
    Rgb radiance(const Vec3& d) const override;
    double intersect(const Vec3&, const Vec3&, double) const override { return -1.0; }

  private:
    Rgb radiance_;
};

class EnvironmentLight final : public Light {
  public:
    // image: linear RGB, width >= 1, height >= 1, every value finite and >= 0
    // (InputError naming `source` and the first bad texel otherwise); scale
    // finite and >= 0; rotateDeg finite. A black image (or scale 0) is
    // allowed: it emits nothing, sample() returns no samples (pdf 0) and
    // pdf() is 0 everywhere.
    EnvironmentLight(Image image, double scale, double rotateDeg, const std::string& source);
    // Reads an OpenEXR (.exr) or Radiance (.hdr) file; InputError naming the
    // file for a missing, unreadable or unsupported file.
    static EnvironmentLight load(const std::string& path, double scale, double rotateDeg);

    bool isInfinite() const override { return true; }
    LightSample sample(const Vec3& p, const std::array<double, 2>& u) const override;
    double pdf(const Vec3& p, const Vec3& wi) const override;
    Rgb radiance(const Vec3& d) const override;
    double intersect(const Vec3&, const Vec3&, double) const override { return -1.0; }

    const Image& image() const { return image_; }

  private:
    // Index (y * width + x) of the texel seen in direction d; *sinTheta (if
    // not null) gets sin theta of d.
    size_t texelOf(const Vec3& d, double* sinTheta) const;

    // The sky's formula (skyLight()): radiance() evaluates it instead of the
    // nearest texel; null for maps read from files.
    friend EnvironmentLight skyLight(double scale, int width, int height);
    Rgb (*exactRadiance_)(const Vec3& mapDirection) = nullptr;

    Image image_;
    double scale_ = 1, rotateRad_ = 0;
    double cosRot_ = 1, sinRot_ = 0;
    bool hasSamples_ = false;  // false for a black image or scale 0
    // Piecewise-constant 2D distribution over the texels: conditional CDFs per
    // row and a marginal CDF over rows (pbrt's Distribution2D).
    std::vector<double> rowCdf_;   // height + 1 entries
    std::vector<double> cellCdf_;  // height * (width + 1) entries
    std::vector<double> cellPdf_;  // height * width: density over [0,1]^2
};

// The procedural sky (docs/scene-format.md, "Procedural sky"): radiance of
// order 1 arriving from the unit direction d, +y up, smooth except for a
// crease at the horizon (continuous there). With y = clamp(d.y, -1, 1):
//   base = Z + (H - Z) (1 - y)^3   for y >= 0  (zenith Z to horizon H)
//        = G + (H - G) (1 + y)^8   for y < 0   (horizon haze to the ground G)
//   L(d) = base + C ((1 + d . s) / 2)^32      (a broad sun-less glow)
// Z = (0.25, 0.45, 0.90) bluish zenith, H = (1.00, 0.97, 0.92) whitish
// horizon, G = (0.20, 0.20, 0.20) dim neutral ground, C = (0.80, 0.70, 0.50)
// warm glow about s = (0, sin 30deg, cos 30deg), 30 degrees above +z (the
// centre column of the lat-long image).
Rgb skyRadiance(const Vec3& d);
// The sky as a lat-long image: every texel is skyRadiance at its centre
// direction (the lat-long convention above). InputError unless width,
// height >= 1 (and at most 2^28 texels).
Image skyImage(int width, int height);
// skyImage(width, height) times scale, unrotated, as an environment light
// (the scene default when no light is given); InputError for a bad scale.
EnvironmentLight skyLight(double scale = 1.0, int width = 256, int height = 128);

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

    const Vec3& center() const { return center_; }
    double radius() const { return radius_; }

  private:
    Vec3 center_;
    double radius_;
    Rgb radiance_;
};

}  // namespace weft::render
