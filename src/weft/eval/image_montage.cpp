#include "weft/eval/image_montage.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/image_io.h"
#include "weft/core/json_message.h"

namespace weft::eval {

void MontageOptions::validate() const {
    if (columns < 0 || columns > kMaxMontageImages)
        throw InputError("--columns " + std::to_string(columns) + " is out of range: allowed [0, " +
                         std::to_string(kMaxMontageImages) + "] (0: one row)");
    if (gap < 0 || gap > 256)
        throw InputError("--gap " + std::to_string(gap) + " is out of range: allowed [0, 256]");
    if (!std::isfinite(exposure) || std::abs(exposure) > 64)
        throw InputError("--exposure " + formatNumber(exposure) +
                         " is out of range: allowed [-64, 64]");
}

Image montage(const std::vector<Image>& images, const std::vector<bool>& isLinear,
              const MontageOptions& options) {
    options.validate();
    if (images.empty()) throw InputError("montage: no images given");
    if (images.size() > static_cast<size_t>(kMaxMontageImages))
        throw InputError("montage: " + std::to_string(images.size()) + " images given: at most " +
                         std::to_string(kMaxMontageImages));
    if (isLinear.size() != images.size())
        throw InputError("montage: one linear/sRGB flag per image is needed");
    const int count = static_cast<int>(images.size());
    const int columns = options.columns == 0 ? count : std::min(options.columns, count);
    const int rows = (count + columns - 1) / columns;
    int cellW = 0, cellH = 0;
    for (const Image& im : images)
        cellW = std::max(cellW, im.width), cellH = std::max(cellH, im.height);
    const int gap = options.gap;
    const int64_t width = int64_t{columns} * (cellW + gap) + gap;
    const int64_t height = int64_t{rows} * (cellH + gap) + gap;
    if (width > 65536 || height > 65536)
        throw InputError("montage: the figure would be " + std::to_string(width) + " x " +
                         std::to_string(height) + " pixels: at most 65536 on each side");
    Image out(static_cast<int>(width), static_cast<int>(height));
    for (int y = 0; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x) out.set(x, y, options.background);
    const double scale = std::exp2(options.exposure);
    for (int i = 0; i < count; ++i) {
        const Image& im = images[i];
        const int x0 = gap + (i % columns) * (cellW + gap) + (cellW - im.width) / 2;
        const int y0 = gap + (i / columns) * (cellH + gap) + (cellH - im.height) / 2;
        const double s = isLinear[i] ? scale : 1.0;
        for (int y = 0; y < im.height; ++y)
            for (int x = 0; x < im.width; ++x) out.set(x0 + x, y0 + y, im.get(x, y) * s);
    }
    return out;
}

}  // namespace weft::eval
