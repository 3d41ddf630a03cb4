// weft/core/image.h — linear RGB float images and their PNG encoding.
//
// Image holds linear RGB in row-major order (row 0 at the top). writePng
// converts to 8-bit sRGB after multiplying by 2^exposure and clamping, and
// writes atomically (temp file + rename). The linear image files (OpenEXR,
// Radiance) are read and written by image_io.h.
#pragma once

#include <string>
#include <vector>

#include "weft/core/rgb.h"

namespace weft {

struct Image {
    int width = 0, height = 0;
    std::vector<float> pixels;  // width * height * 3, linear RGB

    Image() = default;
    Image(int w, int h) : width(w), height(h), pixels(static_cast<size_t>(w) * h * 3, 0.0f) {}

    void set(int x, int y, const Rgb& c) {
        float* p = &pixels[3 * (static_cast<size_t>(y) * width + x)];
        p[0] = static_cast<float>(c.r), p[1] = static_cast<float>(c.g),
        p[2] = static_cast<float>(c.b);
    }
    Rgb get(int x, int y) const {
        const float* p = &pixels[3 * (static_cast<size_t>(y) * width + x)];
        return {p[0], p[1], p[2]};
    }
};

// InputError starting with `what` unless width, height >= 1 and pixels holds
// 3 values per texel.
void checkImage(const Image& image, const std::string& what);

// InputError "<what>: pixel (x, y) channel G is NaN: images must be finite"
// (or "is infinite") for the first value, in row order, that is not finite.
// The image readers (image_io.h) check every image they return with it.
void checkFinitePixels(const Image& image, const std::string& what);

// "fnv1a64:" and 16 hex digits: FNV-1a (core/hash.h) of the pixels' float32
// values as little-endian bytes, in their order in `pixels` (rows from the
// top, R, G, B per texel): what an OpenEXR file of the image holds, so that
// the checksum of the image written equals that of the image read back. The
// checksum a render part's JSON carries (render/render_merge.h).
std::string pixelChecksum(const Image& image);

// The sRGB transfer function of a linear value in [0, 1] (clamped to it).
double linearToSrgb(double v);
// Its inverse: the linear value of an sRGB-encoded value in [0, 1] (clamped to it).
double srgbToLinear(double v);
// Both per channel.
inline Rgb linearToSrgb(const Rgb& c) {
    return Rgb(linearToSrgb(c.r), linearToSrgb(c.g), linearToSrgb(c.b));
}
inline Rgb srgbToLinear(const Rgb& c) {
    return Rgb(srgbToLinear(c.r), srgbToLinear(c.g), srgbToLinear(c.b));
}

// The exposure (stops) at which the 99th percentile of the image's pixel
// luminance maps to kAutoExposureTarget, so that about 1 % of the pixels
// clip (`--exposure auto`); 0 for an image with no positive luminance;
// within [-64, 64].
inline constexpr double kAutoExposureTarget = 0.9;
double autoExposure(const Image& image);
// InputError "<what> <stops> is out of range: allowed [-64, 64] stops, or
// auto" unless the stops are finite and within it.
void checkExposureStops(double stops, const std::string& what);

// PNG bytes of the image (8-bit sRGB, exposure in stops).
std::string encodePng(const Image& image, double exposure = 0.0);
void writePng(const std::string& path, const Image& image, double exposure = 0.0);
// JPEG bytes of the same 8-bit sRGB image at `quality` in [1, 100] (weft
// view's frames: a tenth of the PNG's size for a noisy render).
std::string encodeJpeg(const Image& image, double exposure = 0.0, int quality = 85);

}  // namespace weft
