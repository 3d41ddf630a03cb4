#include "weft/gather/rdm_image.h"

#include <algorithm>
#include <cmath>

#include "weft/core/error.h"
#include "weft/core/math.h"
#include "weft/gather/rdm_io.h"

namespace weft {

Image rdmSliceImage(const float* map, const RdmBins& bins, size_t incidentBin, int scale) {
    Image image(bins.phiO * scale, bins.thetaO * scale);
    const size_t nOut = bins.outgoingCount();
    for (int y = 0; y < image.height; ++y) {
        for (int x = 0; x < image.width; ++x) {
            const size_t cell = (incidentBin * nOut + (y / scale) * bins.phiO + x / scale) * 3;
            image.set(x, y, {map[cell], map[cell + 1], map[cell + 2]});
        }
    }
    return image;
}

double quantileExposure(const Image& image, double q) {
    std::vector<float> values(image.pixels);
    if (values.empty()) return 0.0;
    const size_t k = std::min(values.size() - 1, static_cast<size_t>(q * values.size()));
    std::nth_element(values.begin(), values.begin() + k, values.end());
    return values[k] > 0 ? -std::log2(values[k]) : 0.0;
}

Image rdmComparisonImage(const float* reference, const float* other, const RdmBins& bins,
                         size_t incidentBin, int scale) {
    const Image a = rdmSliceImage(reference, bins, incidentBin, scale);
    const Image b = rdmSliceImage(other, bins, incidentBin, scale);
    const int gap = 4 * scale;
    Image out(2 * a.width + gap, a.height);
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            out.set(x, y, a.get(x, y));
            out.set(a.width + gap + x, y, b.get(x, y));
        }
    return out;
}

size_t writeRdmSlicePng(const std::string& rdmDir, const std::string& component,
                        double thetaIDeg, double phiIDeg, const std::string& pngPath) {
    if (component != "r" && component != "m")
        throw InputError("component \"" + component + "\": allowed r or m");
    if (!(thetaIDeg >= 0 && thetaIDeg <= 90) || !(phiIDeg >= -180 && phiIDeg <= 180))
        throw InputError("incident direction out of range: theta_i in [0, 90], phi_i in "
                         "[-180, 180] degrees");
    const RdmData rdm = loadRdm(rdmDir);
    const RdmBins& bins = rdm.bins;
    const std::vector<float>& map = component == "r" ? rdm.rdmR : rdm.rdmM;
    const size_t bin = bins.incidentBin(sphericalDirection(radians(thetaIDeg), radians(phiIDeg)));
    const Image image = rdmSliceImage(map.data(), bins, bin);
    writePng(pngPath, image, quantileExposure(image));
    return bin;
}

}  // namespace weft
