#include "weft/eval/image_compare.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "weft/core/error.h"
#include "weft/core/image_io.h"

namespace weft::eval {

namespace {

std::string sizeText(int width, int height) {
    return std::to_string(width) + " x " + std::to_string(height);
}

template <typename Value>
Plane toneMapped(const Image& image, double exposure, const Value& value) {
    const double scale = std::exp2(exposure);
    Plane plane(image.width, image.height);
    for (size_t i = 0; i < plane.values.size(); ++i) {
        const float* p = &image.pixels[3 * i];
        plane.values[i] = linearToSrgb(std::clamp(scale * value(p), 0.0, 1.0));
    }
    return plane;
}

// Valid-mode separable filter of `p` with `w` (odd length): (W - n + 1) x
// (H - n + 1) values, value (x, y) = sum_ij w[i] w[j] p(x + i, y + j).
Plane filterValid(const Plane& p, const std::vector<double>& w) {
    const int n = static_cast<int>(w.size());
    const int outW = p.width - n + 1, outH = p.height - n + 1;
    Plane rows(outW, p.height);
    for (int y = 0; y < p.height; ++y)
        for (int x = 0; x < outW; ++x) {
            double sum = 0;
            for (int i = 0; i < n; ++i) sum += w[i] * p.at(x + i, y);
            rows.at(x, y) = sum;
        }
    Plane out(outW, outH);
    for (int y = 0; y < outH; ++y)
        for (int x = 0; x < outW; ++x) {
            double sum = 0;
            for (int j = 0; j < n; ++j) sum += w[j] * rows.at(x, y + j);
            out.at(x, y) = sum;
        }
    return out;
}

Plane product(const Plane& a, const Plane& b) {
    Plane out(a.width, a.height);
    for (size_t i = 0; i < out.values.size(); ++i) out.values[i] = a.values[i] * b.values[i];
    return out;
}

}  // namespace

const char* ssimModeName(SsimMode mode) {
    return mode == SsimMode::Luminance ? "luminance" : "per-channel";
}

Plane toneMappedLuminance(const Image& image, double exposure) {
    return toneMapped(image, exposure,
                      [](const float* p) { return luminance(Rgb(p[0], p[1], p[2])); });
}

Plane toneMappedChannel(const Image& image, int channel, double exposure) {
    if (channel < 0 || channel > 2)
        throw std::invalid_argument("toneMappedChannel: channel " + std::to_string(channel) +
                                    " is outside [0, 2]");
    return toneMapped(image, exposure, [channel](const float* p) { return double(p[channel]); });
}

std::vector<double> ssimWindowWeights() {
    std::vector<double> w(kSsimWindow);
    double sum = 0;
    for (int i = 0; i < kSsimWindow; ++i) {
        const double d = i - kSsimRadius;
        w[i] = std::exp(-d * d / (2 * kSsimSigma * kSsimSigma));
        sum += w[i];
    }
    for (double& v : w) v /= sum;
    return w;
}

Plane ssimMap(const Plane& a, const Plane& b) {
    if (a.width != b.width || a.height != b.height)
        throw std::invalid_argument("ssimMap: planes of different sizes " +
                                    sizeText(a.width, a.height) + " and " +
                                    sizeText(b.width, b.height));
    if (a.width < kSsimWindow || a.height < kSsimWindow)
        throw std::invalid_argument("ssimMap: plane " + sizeText(a.width, a.height) +
                                    " is smaller than the 11 x 11 window");
    const std::vector<double> w = ssimWindowWeights();
    const Plane muA = filterValid(a, w), muB = filterValid(b, w);
    // a*a, b*b and a*b go through the same code, so that identical inputs give
    // bit-identical moments and an SSIM of exactly 1.
    const Plane aa = filterValid(product(a, a), w), bb = filterValid(product(b, b), w);
    const Plane ab = filterValid(product(a, b), w);
    Plane map(muA.width, muA.height);
    for (size_t i = 0; i < map.values.size(); ++i) {
        const double ma = muA.values[i], mb = muB.values[i];
        const double varA = aa.values[i] - ma * ma, varB = bb.values[i] - mb * mb;
        const double cov = ab.values[i] - ma * mb;
        map.values[i] = (2 * ma * mb + kSsimC1) * (2 * cov + kSsimC2) /
                        ((ma * ma + mb * mb + kSsimC1) * (varA + varB + kSsimC2));
    }
    return map;
}

Image boxDownsampled(const Image& image, int factor) {
    if (factor < 1 || image.width < factor || image.height < factor)
        throw std::invalid_argument("boxDownsampled: factor " + std::to_string(factor) +
                                    " does not fit a " + sizeText(image.width, image.height) +
                                    " image");
    Image out(image.width / factor, image.height / factor);
    const double weight = 1.0 / (double(factor) * factor);
    for (int y = 0; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x) {
            double sum[3] = {0, 0, 0};
            for (int j = 0; j < factor; ++j)
                for (int i = 0; i < factor; ++i) {
                    const float* p = &image.pixels[3 * (static_cast<size_t>(y * factor + j) *
                                                            image.width +
                                                        x * factor + i)];
                    for (int c = 0; c < 3; ++c) sum[c] += p[c];
                }
            out.set(x, y, {sum[0] * weight, sum[1] * weight, sum[2] * weight});
        }
    return out;
}

double mean(const Plane& plane) {
    if (plane.values.empty()) return 0;
    double sum = 0;
    for (double v : plane.values) sum += v;
    return sum / static_cast<double>(plane.values.size());
}

double rmse(const Image& a, const Image& b) {
    if (a.pixels.size() != b.pixels.size() || a.pixels.empty())
        throw std::invalid_argument("rmse: images of different or zero sizes");
    double sum = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) {
        const double d = double(a.pixels[i]) - double(b.pixels[i]);
        sum += d * d;
    }
    return std::sqrt(sum / static_cast<double>(a.pixels.size()));
}

double relativeMse(const Image& a, const Image& b) {
    if (a.pixels.size() != b.pixels.size() || a.pixels.empty())
        throw std::invalid_argument("relativeMse: images of different or zero sizes");
    double sum = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) {
        const double ref = b.pixels[i];
        const double d = double(a.pixels[i]) - ref;
        sum += d * d / (ref * ref + kRelMseEpsilon);
    }
    return sum / static_cast<double>(a.pixels.size());
}

void CompareOptions::validate() const {
    if (!std::isfinite(exposure) || std::abs(exposure) > kMaxExposure)
        throw InputError("--exposure " + std::to_string(exposure) +
                         " is out of range: allowed [-64, 64] stops");
    if (scale < 1 || scale > kMaxCompareScale)
        throw InputError("--scale " + std::to_string(scale) +
                         " is out of range: allowed [1, 64] pixels per block side");
}

ImageComparison compareImages(const Image& fullA, const std::string& aName, const Image& fullB,
                              const std::string& bName, const CompareOptions& options) {
    options.validate();
    if (fullA.width != fullB.width || fullA.height != fullB.height)
        throw InputError("image sizes differ: " + aName + " is " +
                         sizeText(fullA.width, fullA.height) + ", the reference " + bName +
                         " is " + sizeText(fullB.width, fullB.height));
    const int k = options.scale;
    if (fullA.width < kSsimWindow * k || fullA.height < kSsimWindow * k)
        throw InputError(aName + " and " + bName + " are " +
                         sizeText(fullA.width, fullA.height) +
                         (k > 1 ? ": at --scale " + std::to_string(k) + " SSIM needs at least " +
                                      sizeText(kSsimWindow * k, kSsimWindow * k) +
                                      " pixels (its 11 x 11 window of " + std::to_string(k) +
                                      " x " + std::to_string(k) + " blocks)"
                                : std::string(": SSIM needs at least 11 x 11 pixels (its window)")));
    // Checked at full resolution, so that the pixel named is the file's own.
    checkFinitePixels(fullA, aName);
    checkFinitePixels(fullB, bName);
    Image downA, downB;
    if (k > 1) downA = boxDownsampled(fullA, k), downB = boxDownsampled(fullB, k);
    const Image& a = k > 1 ? downA : fullA;
    const Image& b = k > 1 ? downB : fullB;

    ImageComparison c;
    c.a = aName, c.b = bName;
    c.width = a.width, c.height = a.height;
    c.mode = options.mode;
    c.exposure = options.exposure;
    c.scale = k;
    if (options.mode == SsimMode::Luminance) {
        c.ssimMap = ssimMap(toneMappedLuminance(a, options.exposure),
                            toneMappedLuminance(b, options.exposure));
    } else {
        for (int channel = 0; channel < 3; ++channel) {
            const Plane m = ssimMap(toneMappedChannel(a, channel, options.exposure),
                                    toneMappedChannel(b, channel, options.exposure));
            if (channel == 0) c.ssimMap = Plane(m.width, m.height);
            for (size_t i = 0; i < m.values.size(); ++i) c.ssimMap.values[i] += m.values[i] / 3;
        }
    }
    c.ssim = mean(c.ssimMap);
    c.rmse = rmse(a, b);
    c.relMse = relativeMse(a, b);
    c.meanA = channelMeans(a), c.meanB = channelMeans(b);
    return c;
}

ImageComparison compareImageFiles(const std::string& a, const std::string& b,
                                  const CompareOptions& options) {
    options.validate();
    const Image imageA = readImageOrPng(a);
    const Image imageB = readImageOrPng(b);
    return compareImages(imageA, a, imageB, b, options);
}

Rgb channelMeans(const Image& image) {
    Rgb sum;
    const size_t pixels = image.pixels.size() / 3;
    for (size_t i = 0; i < pixels; ++i)
        for (int channel = 0; channel < 3; ++channel) sum[channel] += image.pixels[3 * i + channel];
    return pixels > 0 ? sum / static_cast<double>(pixels) : sum;
}

nlohmann::json toJson(const ImageComparison& c) {
    nlohmann::json ratio = nlohmann::json::array();
    for (int channel = 0; channel < 3; ++channel)
        ratio.push_back(c.meanB[channel] != 0 ? nlohmann::json(c.meanA[channel] / c.meanB[channel])
                                              : nlohmann::json(nullptr));
    return {{"a", c.a},
            {"b", c.b},
            {"width", c.width},
            {"height", c.height},
            {"ssim", c.ssim},
            {"ssim_mode", ssimModeName(c.mode)},
            {"rmse", c.rmse},
            {"rel_mse", c.relMse},
            {"mean_a", {c.meanA.r, c.meanA.g, c.meanA.b}},
            {"mean_b", {c.meanB.r, c.meanB.g, c.meanB.b}},
            {"mean_ratio", ratio},
            {"exposure", c.exposure},
            {"scale", c.scale}};
}

Rgb heatmapColorSrgb(double t) {
    // viridis at t = k/8 (viridisLite's viridis(9)), 8-bit sRGB.
    static constexpr std::array<std::array<int, 3>, 9> kViridis = {{{0x44, 0x01, 0x54},
                                                                    {0x47, 0x2d, 0x7b},
                                                                    {0x3b, 0x52, 0x8b},
                                                                    {0x2c, 0x72, 0x8e},
                                                                    {0x21, 0x90, 0x8c},
                                                                    {0x27, 0xad, 0x81},
                                                                    {0x5d, 0xc8, 0x63},
                                                                    {0xaa, 0xdc, 0x32},
                                                                    {0xfd, 0xe7, 0x25}}};
    const double s = (std::isnan(t) ? 1.0 : std::clamp(t, 0.0, 1.0)) * (kViridis.size() - 1);
    const int k = std::min(static_cast<int>(s), static_cast<int>(kViridis.size()) - 2);
    const double f = s - k;
    double c[3];
    for (int i = 0; i < 3; ++i) c[i] = ((1 - f) * kViridis[k][i] + f * kViridis[k + 1][i]) / 255.0;
    return {c[0], c[1], c[2]};
}

Image ssimHeatmap(const ImageComparison& c) {
    if (c.ssimMap.width != c.width - 2 * kSsimRadius ||
        c.ssimMap.height != c.height - 2 * kSsimRadius || c.ssimMap.width < 1 ||
        c.ssimMap.height < 1)
        throw std::invalid_argument("ssimHeatmap: the SSIM map does not fit a " +
                                    sizeText(c.width, c.height) + " image");
    Image image(c.width, c.height);
    for (int y = 0; y < c.height; ++y)
        for (int x = 0; x < c.width; ++x) {
            const int mx = std::clamp(x, kSsimRadius, c.width - 1 - kSsimRadius) - kSsimRadius;
            const int my = std::clamp(y, kSsimRadius, c.height - 1 - kSsimRadius) - kSsimRadius;
            const Rgb srgb = heatmapColorSrgb(1 - c.ssimMap.at(mx, my));
            image.set(x, y, srgbToLinear(srgb));
        }
    return image;
}

}  // namespace weft::eval
