// weft/gather/rdm_image.h — pictures of RDM slices (paper Fig. 2).
//
// A slice is the outgoing map of one incident bin: TO x PO cells, drawn as a
// latitude-longitude image (x: phi_o from -180 to 180 degrees, y: theta_o
// from 0 at the top, along the entry normal, to 180 degrees), each cell
// `scale` pixels wide.
#pragma once

#include <string>

#include "weft/core/image.h"
#include "weft/gather/rdm.h"

namespace weft {

// map: (TI, PI, TO, PO, 3) float32 as in rdm_r.npy / rdm_m.npy.
Image rdmSliceImage(const float* map, const RdmBins& bins, size_t incidentBin, int scale = 4);

// Exposure (log2 scale for writePng) that maps the q-quantile of the image's
// values to white; 0 for an all-black image.
double quantileExposure(const Image& image, double q = 0.99);

// Two slices of the same incident bin side by side, `reference` on the left
// and `other` on the right, with a black gap of 4 cells between them.
Image rdmComparisonImage(const float* reference, const float* other, const RdmBins& bins,
                         size_t incidentBin, int scale = 4);

// Loads DIR (loadRdm: validated) and, for component "r" or "m",
// writes the slice of that map for the incident bin containing (thetaIDeg, phiIDeg) as a
// PNG, auto-exposed to the 99th percentile. Returns that bin's index.
size_t writeRdmSlicePng(const std::string& rdmDir, const std::string& component,
                        double thetaIDeg, double phiIDeg, const std::string& pngPath);

}  // namespace weft
