// weft/eval/image_compare.h — an image against a reference: SSIM, RMSE and
// relative MSE, and an SSIM heatmap (issue 8, docs/design.md 9; docs/compare.md).
//
// SSIM (Wang, Bovik, Sheikh, Simoncelli 2004, eqs. 13-16): for every 11 x 11
// window w with Gaussian weights (sigma 1.5, normalised to sum 1),
//
//     SSIM = (2 mu_a mu_b + C1) (2 sigma_ab + C2)
//            / ((mu_a^2 + mu_b^2 + C1) (sigma_a^2 + sigma_b^2 + C2)),
//
// mu the weighted means, sigma^2 and sigma_ab the weighted (biased) variances
// and covariance, C1 = (0.01 L)^2, C2 = (0.03 L)^2 with dynamic range L = 1.
// The map holds only windows that lie wholly inside the image (the "valid"
// region, (W - 10) x (H - 10) values, as scikit-image after its crop), so no
// padding rule enters the score; the mean SSIM is the mean of the map.
//
// What SSIM compares is tone-mapped: the linear image times 2^exposure, as
// luminance Y = 0.2126 R + 0.7152 G + 0.0722 B (default) or per channel,
// clamped to [0, 1] and sRGB-encoded. Per channel, the three maps are
// averaged pixel by pixel.
//
// RMSE and relative MSE are over every pixel and channel of the linear
// images (no exposure): sqrt(mean (a - b)^2) and mean (a - b)^2 / (b^2 + 0.01),
// b being the reference.
//
// With scale K > 1 both linear images are first averaged over K x K pixel
// blocks (a box filter, the partial blocks of the right and bottom edges
// dropped), so every metric sees only structure larger than K pixels: how a
// ply-level model, which averages over the fibers of a ply, compares at the
// scale of the ply rather than of one fiber (docs/compare.md, "Scale").
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "weft/core/image.h"
#include "weft/core/rgb.h"

namespace weft::eval {

constexpr int kSsimWindow = 11;                      // window side, pixels
constexpr int kSsimRadius = kSsimWindow / 2;         // 5
constexpr double kSsimSigma = 1.5;                   // Gaussian window, pixels
constexpr double kSsimC1 = (0.01 * 1) * (0.01 * 1);  // (K1 L)^2, L = 1
constexpr double kSsimC2 = (0.03 * 1) * (0.03 * 1);  // (K2 L)^2
constexpr double kRelMseEpsilon = 1e-2;              // added to b^2 in relative MSE
constexpr double kMaxExposure = 64;                  // |exposure| in stops
constexpr int kMaxCompareScale = 64;                 // --scale, pixels per block side

enum class SsimMode { Luminance, PerChannel };

// "luminance" or "per-channel".
const char* ssimModeName(SsimMode mode);

// A single-channel image of doubles, row-major (row 0 at the top).
struct Plane {
    int width = 0, height = 0;
    std::vector<double> values;  // width * height

    Plane() = default;
    Plane(int w, int h) : width(w), height(h), values(static_cast<size_t>(w) * h, 0.0) {}
    double& at(int x, int y) { return values[static_cast<size_t>(y) * width + x]; }
    double at(int x, int y) const { return values[static_cast<size_t>(y) * width + x]; }
};

// The tone-mapped luminance of a linear image: linearToSrgb(clamp(2^exposure
// * Y, 0, 1)).
Plane toneMappedLuminance(const Image& image, double exposure);
// The same for one channel (0 = R, 1 = G, 2 = B) instead of Y.
Plane toneMappedChannel(const Image& image, int channel, double exposure);

// The 11 x 11 Gaussian window's weights along one axis (normalised; the 2D
// weights are their outer product).
std::vector<double> ssimWindowWeights();

// The SSIM map of two planes of one size, at least 11 x 11: (W - 10) x
// (H - 10) values, value (x, y) for the window centred on pixel (x + 5, y + 5).
// std::invalid_argument otherwise (callers validate user input first).
Plane ssimMap(const Plane& a, const Plane& b);

// The image averaged over factor x factor blocks of pixels: floor(W / factor)
// x floor(H / factor) pixels, each the mean of its block (linear RGB); the
// partial blocks at the right and bottom edges are dropped. std::invalid_argument
// unless factor >= 1 and the image has at least one whole block.
Image boxDownsampled(const Image& image, int factor);

// The mean of the values (0 for an empty plane).
double mean(const Plane& plane);
// The mean of each channel over every pixel (0 for an empty image).
Rgb channelMeans(const Image& image);

// sqrt of the mean of (a - b)^2 over every pixel and channel.
double rmse(const Image& a, const Image& b);
// The mean of (a - b)^2 / (b^2 + 0.01) over every pixel and channel; b is the reference.
double relativeMse(const Image& a, const Image& b);

struct CompareOptions {
    SsimMode mode = SsimMode::Luminance;
    double exposure = 0;  // stops, applied before the tone map of SSIM
    int scale = 1;        // both images box-downsampled by this factor first; [1, 64]

    // InputError naming --exposure unless it is finite and within [-64, 64],
    // and naming --scale unless it is within [1, 64].
    void validate() const;
};

struct ImageComparison {
    std::string a, b;           // names (paths) of the image and of the reference
    int width = 0, height = 0;  // of the compared images: the inputs' divided by scale
    SsimMode mode = SsimMode::Luminance;
    double exposure = 0;
    int scale = 1;
    double ssim = 0;    // mean of ssimMap
    double rmse = 0;    // linear
    double relMse = 0;  // linear
    // Linear channel means of both images: their ratio a / b tells a bias
    // (a brighter or darker render) from noise, which averages out.
    Rgb meanA, meanB;
    Plane ssimMap;  // the valid region, (width - 10) x (height - 10)
};

// Compares `a` (named aName in messages) against the reference `b`, both
// box-downsampled by options.scale first. InputError naming the file(s) when
// the sizes differ, an image (after the downsampling) is smaller than 11 x 11,
// or a pixel is NaN or infinite (the first one, x, y and channel).
ImageComparison compareImages(const Image& a, const std::string& aName, const Image& b,
                              const std::string& bName, const CompareOptions& options);
// The same for two files read with readImageOrPng (core/image_io.h: .exr or
// .hdr linear; .png decoded from sRGB, for figures whose renders are gone:
// SSIM then sees the PNG's own 8-bit values, RMSE and relative MSE the clipped
// display values rather than radiance).
ImageComparison compareImageFiles(const std::string& a, const std::string& b,
                                  const CompareOptions& options);

// {"a", "b", "width", "height", "ssim", "ssim_mode", "rmse", "rel_mse", "mean_a",
// "mean_b", "mean_ratio" (per channel mean_a / mean_b, null where mean_b is 0),
// "exposure", "scale"}.
nlohmann::json toJson(const ImageComparison& comparison);

// The heatmap colour scale: viridis sampled at t = k/8, k = 0..8 (the nine
// colours of viridisLite's viridis(9)), interpolated linearly in sRGB between
// them; t is clamped to [0, 1]. Returns sRGB-encoded values in [0, 1].
Rgb heatmapColorSrgb(double t);

// The heatmap of a comparison: width x height, pixel colour
// heatmapColorSrgb(1 - SSIM) (stored linear, so that writePng at exposure 0
// writes those sRGB values). Pixels outside the valid region take the value of
// the nearest valid pixel (coordinates clamped to [5, W - 6] x [5, H - 6]).
Image ssimHeatmap(const ImageComparison& comparison);

}  // namespace weft::eval
