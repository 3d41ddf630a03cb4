#include "weft/render/environment_light.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "weft/core/error.h"
#include "weft/core/image_io.h"
#include "weft/core/math.h"
#include "weft/render/scene_limits.h"
#include "weft/render/scene_reader.h"

namespace weft::render {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The cell of t in [0, 1] on a grid of n cells; NaN and out-of-range values clamp.
int cellIndex(double t, int n) {
    if (!(t > 0)) return 0;
    if (t >= 1) return n - 1;
    return std::min(static_cast<int>(t * n), n - 1);
}

// R_y(angle) d for the (cos, sin) of the angle: +z turns towards +x.
Vec3 rotateY(const Vec3& d, double cosA, double sinA) {
    return {cosA * d.x + sinA * d.z, d.y, -sinA * d.x + cosA * d.z};
}

// Largest i in [0, n - 1] with cdf[i] <= u (pbrt's FindInterval): cells of zero
// probability have cdf[i] == cdf[i + 1] and are never returned for u < 1.
int findInterval(const double* cdf, int n, double u) {
    const double* it = std::upper_bound(cdf, cdf + n + 1, u);
    return std::clamp(static_cast<int>(it - cdf) - 1, 0, n - 1);
}

// Samples a piecewise-constant 1D distribution over [0, 1) given by its CDF
// (n + 1 entries, cdf[n] = 1): the continuous position in [0, 1) and its cell.
double sampleContinuous(const double* cdf, int n, double u, int* cell) {
    const int i = findInterval(cdf, n, u);
    const double width = cdf[i + 1] - cdf[i];
    const double frac = width > 0 ? std::clamp((u - cdf[i]) / width, 0.0, kOneMinusEpsilon) : 0.0;
    *cell = i;
    return (i + frac) / n;
}

}  // namespace

// ---------------------------------------------------------------------------
// EnvironmentLight

EnvironmentLight::EnvironmentLight(Image image, double scale, double rotateDeg,
                                   const std::string& source)
    : image_(std::move(image)), scale_(scale), rotateRad_(radians(rotateDeg)) {
    const std::string what = "envmap '" + source + "'";
    checkImage(image_, what);
    if (!(std::isfinite(scale) && scale >= 0))
        throw InputError(what + ": scale = " + streamedText(scale) + " must be finite and >= 0");
    if (!std::isfinite(rotateDeg))
        throw InputError(what + ": rotate_deg = " + streamedText(rotateDeg) + " must be finite");
    const int w = image_.width, h = image_.height;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) {
                const double v = image_.pixels[3 * (size_t(y) * w + x) + c];
                if (!(std::isfinite(v) && v >= 0 && v * scale <= kMaxRadiance))
                    throw InputError(what + ": texel (x " + std::to_string(x) + ", y " +
                                     std::to_string(y) + ") channel " + "RGB"[c] + " = " +
                                     streamedText(v) + " must be finite, >= 0 and, times scale " +
                                     streamedText(scale) + ", at most " +
                                     streamedText(kMaxRadiance));
            }
    cosRot_ = std::cos(rotateRad_);
    sinRot_ = std::sin(rotateRad_);

    // pbrt-v3's InfiniteAreaLight: texel weight = luminance * sin(theta of the
    // row centre), so that the density in solid angle (divided by sin theta)
    // follows the luminance. Unnormalised cumulative sums first, divided
    // afterwards, so that cells of zero weight keep exactly equal CDF values.
    rowCdf_.assign(h + 1, 0.0);
    cellCdf_.assign(size_t(h) * (w + 1), 0.0);
    cellPdf_.assign(size_t(h) * w, 0.0);
    std::vector<double> rowWeight(h, 0.0);
    for (int y = 0; y < h; ++y) {
        const double sinTheta = std::sin(kPi * (y + 0.5) / h);
        double* cdf = &cellCdf_[size_t(y) * (w + 1)];
        for (int x = 0; x < w; ++x) {
            const double f = luminance(image_.get(x, y)) * sinTheta;
            cellPdf_[size_t(y) * w + x] = f;
            cdf[x + 1] = cdf[x] + f;
        }
        rowWeight[y] = cdf[w];
        if (cdf[w] > 0)
            for (int x = 1; x <= w; ++x) cdf[x] /= rowWeight[y];
        rowCdf_[y + 1] = rowCdf_[y] + rowWeight[y];
    }
    const double total = rowCdf_[h];
    if (!(total > 0) || scale_ == 0) {
        // Nothing to emit: no samples, pdf 0 everywhere.
        cellPdf_.assign(cellPdf_.size(), 0.0);
        return;
    }
    for (int y = 1; y <= h; ++y) rowCdf_[y] /= total;
    // Density over [0, 1]^2: f / (mean of f) = f * w * h / total.
    const double norm = double(w) * h / total;
    for (double& f : cellPdf_) f *= norm;
    hasSamples_ = true;
}

EnvironmentLight EnvironmentLight::load(const std::string& path, double scale, double rotateDeg) {
    return EnvironmentLight(readImage(path), scale, rotateDeg, path);
}

size_t EnvironmentLight::texelOf(const Vec3& d, double* sinTheta) const {
    // Into the frame of the unrotated map: R_y(-rotate) d.
    const Vec3 m = rotateY(d, cosRot_, -sinRot_);
    double u = std::atan2(m.x, -m.z) * (0.5 * kInvPi);
    if (u < 0) u += 1.0;
    const double v = safeAcos(m.y) * kInvPi;
    if (sinTheta) *sinTheta = std::sqrt(m.x * m.x + m.z * m.z);
    return size_t(cellIndex(v, image_.height)) * image_.width + cellIndex(u, image_.width);
}

LightSample EnvironmentLight::sample(const Vec3& p, const std::array<double, 2>& u) const {
    if (!hasSamples_) return {};
    const int w = image_.width, h = image_.height;
    const double u0 = std::clamp(u[0], 0.0, kOneMinusEpsilon);
    const double u1 = std::clamp(u[1], 0.0, kOneMinusEpsilon);
    // The row from the marginal, then the column from that row's conditional
    // (pbrt's Distribution2D::SampleContinuous).
    int row = 0, column = 0;
    const double v = sampleContinuous(rowCdf_.data(), h, u1, &row);
    const double uu = sampleContinuous(&cellCdf_[size_t(row) * (w + 1)], w, u0, &column);
    const double theta = kPi * v, phi = kTwoPi * uu;
    const double sinTheta = std::sin(theta);
    const Vec3 m{sinTheta * std::sin(phi), std::cos(theta), -sinTheta * std::cos(phi)};
    LightSample s;
    s.wi = rotateY(m, cosRot_, sinRot_);
    // Density and radiance from wi itself, so that they agree with pdf() and
    // radiance() even where rounding puts wi on a neighbouring texel.
    s.pdf = pdf(p, s.wi);
    if (!(s.pdf > 0)) return {};
    s.radiance = radiance(s.wi);
    s.distance = kInf;
    return s;
}

double EnvironmentLight::pdf(const Vec3&, const Vec3& wi) const {
    if (!hasSamples_) return 0;
    double sinTheta = 0;
    const size_t texel = texelOf(wi, &sinTheta);
    if (!(sinTheta > 0)) return 0;
    // d omega = 2 pi^2 sin(theta) du dv for u = phi / (2 pi), v = theta / pi.
    return cellPdf_[texel] / (2.0 * kPi * kPi * sinTheta);
}

Rgb EnvironmentLight::radiance(const Vec3& d) const {
    if (exactRadiance_) return exactRadiance_(rotateY(d, cosRot_, -sinRot_)) * scale_;
    const size_t texel = texelOf(d, nullptr);
    const float* px = &image_.pixels[3 * texel];
    return Rgb(px[0], px[1], px[2]) * scale_;
}

// ---------------------------------------------------------------------------
// The procedural sky

Rgb skyRadiance(const Vec3& d) {
    constexpr Rgb kZenith{0.25, 0.45, 0.90}, kHorizon{1.00, 0.97, 0.92}, kGround{0.20, 0.20, 0.20};
    constexpr Rgb kGlow{0.80, 0.70, 0.50};
    const Vec3 glowDir{0.0, 0.5, 0.8660254037844386};  // 30 degrees above +z
    const double y = std::clamp(d.y, -1.0, 1.0);
    // Integer powers by multiplication (std::pow was a visible share of a render's time).
    auto square = [](double x) { return x * x; };
    const Rgb base = y >= 0 ? kZenith + (kHorizon - kZenith) * ((1.0 - y) * square(1.0 - y))
                            : kGround + (kHorizon - kGround) * square(square(square(1.0 + y)));
    const double c = std::clamp(0.5 * (1.0 + dot(d, glowDir)), 0.0, 1.0);
    return base + kGlow * square(square(square(square(square(c)))));
}

Image skyImage(int width, int height) {
    if (width < 1 || height < 1 || int64_t(width) * height > kMaxImagePixels)
        throw InputError("procedural sky: image size " + std::to_string(width) + " x " +
                         std::to_string(height) + " must be at least 1 x 1 and at most " +
                         std::to_string(kMaxImagePixels) + " texels");
    Image image(width, height);
    for (int y = 0; y < height; ++y) {
        const double theta = kPi * (y + 0.5) / height;
        for (int x = 0; x < width; ++x) {
            const double phi = kTwoPi * (x + 0.5) / width;
            const Vec3 d{std::sin(theta) * std::sin(phi), std::cos(theta),
                         -std::sin(theta) * std::cos(phi)};
            image.set(x, y, skyRadiance(d));
        }
    }
    return image;
}

EnvironmentLight skyLight(double scale, int width, int height) {
    EnvironmentLight sky(skyImage(width, height), scale, 0.0, "procedural sky");
    sky.exactRadiance_ = &skyRadiance;
    return sky;
}

// ---------------------------------------------------------------------------
// The scene types

nlohmann::json EnvmapLightDesc::params() const {
    return {{"file", file}, {"scale", scale}, {"rotate_deg", rotateDeg}};
}

std::unique_ptr<Light> EnvmapLightDesc::create() const {
    return std::make_unique<EnvironmentLight>(EnvironmentLight::load(file, scale, rotateDeg));
}

nlohmann::json SkyLightDesc::params() const { return {{"scale", scale}}; }

std::unique_ptr<Light> SkyLightDesc::create() const {
    return std::make_unique<EnvironmentLight>(skyLight(scale));
}

LightType envmapLightType() {
    return {"envmap", [](JsonObjectReader& r, const std::string& baseDir) {
                r.allowKeys({"type", "file", "scale", "rotate_deg"});
                auto l = std::make_shared<EnvmapLightDesc>();
                l->file = readFileName(r, "file", baseDir, {".exr", ".hdr"});
                if (r.has("rotate_deg"))
                    l->rotateDeg = r.number("rotate_deg", NumberRange::closed(-3600, 3600));
                if (r.has("scale")) l->scale = r.number("scale", NumberRange::closed(0, kMaxRadiance));
                return std::shared_ptr<const LightDesc>(l);
            }};
}

LightType skyLightType() {
    return {"sky", [](JsonObjectReader& r, const std::string&) {
                r.allowKeys({"type", "scale"});
                auto l = std::make_shared<SkyLightDesc>();
                if (r.has("scale")) l->scale = r.number("scale", NumberRange::closed(0, kMaxRadiance));
                return std::shared_ptr<const LightDesc>(l);
            }};
}

Rgb EnvironmentLight::power(double sceneRadius) const {
    return averageRadiance(*this) * (4.0 * kPi * kPi * sceneRadius * sceneRadius);
}

}  // namespace weft::render
