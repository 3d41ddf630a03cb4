// weft/render/environment_light.h — light from every direction, from an image
// or the procedural sky. Scene types:
//   {"type": "envmap", "file": "sky.exr", "scale": 1, "rotate_deg": 0}
//       a lat-long RGB image (OpenEXR or Radiance .hdr; "file" required,
//       relative to the scene file) times `scale` ([0, 1e6]), rotated by
//       `rotate_deg` ([-3600, 3600]) about +y;
//   {"type": "sky", "scale": 1}
//       the procedural sky (skyLight() below), the scene's light when it names none.
//
//   EnvironmentLight  a lat-long RGB image times `scale`, rotated about +y;
//                     importance sampled with a piecewise-constant 2D
//                     distribution over the texels (luminance times sin
//                     theta of the row), whose density is exactly what pdf()
//                     returns. Radiance is piecewise constant (nearest
//                     texel), so sampling and lookup agree.
//   The procedural sky (skyLight()) is an EnvironmentLight over an image
//                     computed from a documented analytic formula (docs/scene-format.md,
//                     "Procedural sky"; see skyRadiance below). It is importance
//                     sampled by that image's texels like any map, but its
//                     radiance is the formula itself at the exact direction, so
//                     it is smooth (a nearest-texel lookup shows bands) and the
//                     pdf stays exactly what sample() draws from.
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
#pragma once

#include <string>
#include <vector>

#include "weft/core/image.h"
#include "weft/render/light.h"

namespace weft::render {

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
    Rgb power(double sceneRadius) const override;

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

struct EnvmapLightDesc final : LightDesc {
    std::string file;  // resolved path
    double scale = 1, rotateDeg = 0;

    const char* type() const override { return "envmap"; }
    nlohmann::json params() const override;
    std::vector<std::pair<std::string, std::string>> files() const override {
        return {{"file", file}};
    }
    std::unique_ptr<Light> create() const override;
};

struct SkyLightDesc final : LightDesc {
    double scale = 1;

    const char* type() const override { return "sky"; }
    nlohmann::json params() const override;
    std::unique_ptr<Light> create() const override;
};

// Their registrations (light_types.cpp).
LightType envmapLightType();
LightType skyLightType();

}  // namespace weft::render
