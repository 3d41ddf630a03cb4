// weft/render/lights.h — the light sources of a cloth scene (issue 7, DESIGN.md 8).
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
//                     computed from a documented analytic formula (docs/scene-format.md).
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
// direction d sees the unrotated map at R_y(-rotate_deg) d.
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
    // finite and >= 0; rotateDeg finite. A black image is allowed (it emits
    // nothing and sample() returns no samples).
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
    Image image_;
    double scale_ = 1, rotateRad_ = 0;
    // Piecewise-constant 2D distribution over the texels: conditional CDFs per
    // row and a marginal CDF over rows (pbrt's Distribution2D).
    std::vector<double> rowCdf_;   // height + 1 entries
    std::vector<double> cellCdf_;  // height * (width + 1) entries
    std::vector<double> cellPdf_;  // height * width: density over [0,1]^2
};

// The procedural sky of docs/scene-format.md, times scale, as an environment
// light (the scene default when no light is given).
EnvironmentLight skyLight(double scale = 1.0, int width = 256, int height = 128);

class SphereLight final : public Light {
public:
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

// Reads a linear RGB image: OpenEXR (.exr, RGB or RGBA channels, any pixel
// type; alpha ignored; a Y-only file is grey) or Radiance RGBE (.hdr); the
// extension picks the reader (case-insensitive). InputError naming the file.
Image readImage(const std::string& path);
// Writes linear RGB as an OpenEXR file with 32-bit float R, G, B channels,
// atomically (temp file + rename).
void writeExr(const std::string& path, const Image& image);

}  // namespace weft::render
