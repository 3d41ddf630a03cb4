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
    Image image = rdmSliceImage(map.data(), bins, bin);
    std::vector<float> values(image.pixels);
    const size_t k = values.size() * 99 / 100;
    std::nth_element(values.begin(), values.begin() + k, values.end());
    const double white = values[k] > 0 ? values[k] : 1.0;
    writePng(pngPath, image, -std::log2(white));
    return bin;
}

}  // namespace weft
