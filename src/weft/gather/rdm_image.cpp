#include "weft/gather/rdm_image.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/math.h"
#include "weft/core/npy.h"

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
    const std::string metaPath = (std::filesystem::path(rdmDir) / "meta.json").string();
    nlohmann::json meta;
    try {
        meta = nlohmann::json::parse(readFile(metaPath));
    } catch (const nlohmann::json::exception& e) {
        throw InputError(metaPath + ": malformed JSON: " + e.what());
    }
    const auto& b = meta.at("bins");
    if (!b.is_array() || b.size() != 4) throw InputError(metaPath + ": \"bins\" must hold 4 integers");
    RdmBins bins{b[0].get<int>(), b[1].get<int>(), b[2].get<int>(), b[3].get<int>()};
    bins.validate();
    const std::string mapPath = (std::filesystem::path(rdmDir) / ("rdm_" + component + ".npy")).string();
    const NpyArray array = readNpy(mapPath);
    const std::vector<size_t> shape = {size_t(bins.thetaI), size_t(bins.phiI), size_t(bins.thetaO),
                                       size_t(bins.phiO), 3};
    if (array.descr != "<f4" || array.shape != shape)
        throw InputError(mapPath + ": expected float32 of shape " + npyShapeString(shape) +
                         ", got " + array.descr + " " + npyShapeString(array.shape));
    const size_t bin = bins.incidentBin(sphericalDirection(radians(thetaIDeg), radians(phiIDeg)));
    Image image = rdmSliceImage(reinterpret_cast<const float*>(array.bytes.data()), bins, bin);
    std::vector<float> values(image.pixels);
    const size_t k = values.size() * 99 / 100;
    std::nth_element(values.begin(), values.begin() + k, values.end());
    const double white = values[k] > 0 ? values[k] : 1.0;
    writePng(pngPath, image, -std::log2(white));
    return bin;
}

}  // namespace weft
