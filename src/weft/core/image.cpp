#include "weft/core/image.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <string_view>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/hash.h"
#include "weft/core/json_message.h"

#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STBI_WRITE_NO_STDIO
#include <stb/stb_image_write.h>

namespace weft {

void checkImage(const Image& image, const std::string& what) {
    if (image.width < 1 || image.height < 1 ||
        image.pixels.size() != 3 * static_cast<size_t>(image.width) * image.height)
        throw InputError(what + ": image of " + std::to_string(image.width) + " x " +
                         std::to_string(image.height) + " texels with " +
                         std::to_string(image.pixels.size()) +
                         " values; expected width, height >= 1 and 3 values per texel");
}

void checkFinitePixels(const Image& image, const std::string& what) {
    static const char* channels[3] = {"R", "G", "B"};
    for (size_t i = 0; i < image.pixels.size(); ++i) {
        if (std::isfinite(image.pixels[i])) continue;
        const size_t pixel = i / 3;
        const size_t width = static_cast<size_t>(std::max(image.width, 1));
        throw InputError(what + ": pixel (" + std::to_string(pixel % width) + ", " +
                         std::to_string(pixel / width) + ") channel " + channels[i % 3] + " is " +
                         (std::isnan(image.pixels[i]) ? "NaN" : "infinite") +
                         ": images must be finite");
    }
}

std::string pixelChecksum(const Image& image) {
    static_assert(std::endian::native == std::endian::little && sizeof(float) == 4,
                  "the checksum is of little-endian float32 bytes");
    const std::string_view bytes(reinterpret_cast<const char*>(image.pixels.data()),
                                 image.pixels.size() * sizeof(float));
    return "fnv1a64:" + hex16(fnv1a64(bytes));
}

double linearToSrgb(double v) {
    v = std::clamp(v, 0.0, 1.0);
    return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

double srgbToLinear(double v) {
    v = std::clamp(v, 0.0, 1.0);
    return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

double autoExposure(const Image& image) {
    std::vector<double> lum;
    lum.reserve(image.pixels.size() / 3);
    for (size_t i = 0; i + 2 < image.pixels.size(); i += 3)
        lum.push_back(luminance({image.pixels[i], image.pixels[i + 1], image.pixels[i + 2]}));
    if (lum.empty()) return 0;
    const size_t k =
        std::min(lum.size() - 1, static_cast<size_t>(0.99 * static_cast<double>(lum.size())));
    std::nth_element(lum.begin(), lum.begin() + static_cast<std::ptrdiff_t>(k), lum.end());
    const double p99 = lum[k];
    if (!(p99 > 0) || !std::isfinite(p99)) return 0;
    return std::clamp(std::log2(kAutoExposureTarget / p99), -64.0, 64.0);
}

void checkExposureStops(double stops, const std::string& what) {
    if (!std::isfinite(stops) || std::abs(stops) > 64)
        throw InputError(what + " " + formatNumber(stops) +
                         " is out of range: allowed [-64, 64] stops, or auto");
}

namespace {

// The image tone-mapped as the PNG shows it: exposure, then 8-bit sRGB.
std::vector<unsigned char> displayBytes(const Image& image, double exposure, const char* format) {
    if (image.width <= 0 || image.height <= 0)
        throw InputError(std::string("cannot encode an empty image as ") + format);
    const double scale = std::exp2(exposure);
    std::vector<unsigned char> bytes(image.pixels.size());
    for (size_t i = 0; i < bytes.size(); ++i) {
        const double v = std::isfinite(image.pixels[i]) ? image.pixels[i] * scale : 0.0;
        bytes[i] = static_cast<unsigned char>(std::lround(255.0 * linearToSrgb(v)));
    }
    return bytes;
}

void appendBytes(void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), size);
}

}  // namespace

std::string encodePng(const Image& image, double exposure) {
    const std::vector<unsigned char> bytes = displayBytes(image, exposure, "PNG");
    std::string out;
    if (!stbi_write_png_to_func(appendBytes, &out, image.width, image.height, 3, bytes.data(),
                                image.width * 3))
        throw std::runtime_error("PNG encoding failed");
    return out;
}

std::string encodeJpeg(const Image& image, double exposure, int quality) {
    const std::vector<unsigned char> bytes = displayBytes(image, exposure, "JPEG");
    std::string out;
    if (!stbi_write_jpg_to_func(appendBytes, &out, image.width, image.height, 3, bytes.data(),
                                std::clamp(quality, 1, 100)))
        throw std::runtime_error("JPEG encoding failed");
    return out;
}

void writePng(const std::string& path, const Image& image, double exposure) {
    writeFileAtomic(path, encodePng(image, exposure));
}

}  // namespace weft
