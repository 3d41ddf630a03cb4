// weft/eval/image_montage.h — side-by-side figures of renders and heatmaps
// (`weft montage`, the paper's Fig. 8/9 layout: reference | neural | heatmap
// | equal-time fiber).
//
// Images are placed left to right in rows of `columns`, each centred in a
// cell as large as the largest image, with `gap` pixels of background
// between cells and around the figure. Linear inputs (.exr, .hdr) are scaled
// by 2^exposure; sRGB inputs (.png, e.g. a heatmap of `weft compare`) are
// decoded to linear so that writePng gives back their 8-bit values exactly.
#pragma once

#include <string>
#include <vector>

#include "weft/core/image.h"

namespace weft::eval {

inline constexpr int kMaxMontageImages = 64;

struct MontageOptions {
    int columns = 0;          // images per row; 0 = all in one row; [0, 64]
    int gap = 4;              // pixels between and around cells; [0, 256]
    double exposure = 0;      // stops for linear inputs; [-64, 64]
    Rgb background{1, 1, 1};  // linear RGB of the gaps

    void validate() const;  // InputError naming the flag and its range
};

// The figure; InputError when `images` is empty or has more than 64 entries.
Image montage(const std::vector<Image>& images, const std::vector<bool>& isLinear,
              const MontageOptions& options);

}  // namespace weft::eval
