// weft/core/bsdf.h — the one BSDF contract shared by the fiber and yarn models.
//
// Directions follow Mitsuba/pbrt (DESIGN.md 2): wi points towards the previous
// path vertex (camera side), wo towards the next one (light side), both unit
// vectors in the model's local frame.
//   eval(wi, wo)  -> Rgb  scattering value, foreshortening of wo included
//   pdf(wi, wo)   -> solid-angle density of sample() for the continuous lobes
//   sample(wi, u) -> BsdfSample with weight = eval / pdf computed in one place
// A sample with pdf == 0 and a black weight is an invalid (absorbed) sample.
#pragma once

#include <array>

#include "weft/core/rgb.h"
#include "weft/core/vec.h"

namespace weft {

// Three uniform numbers in [0, 1) that drive one call to sample(): the first
// picks the lobe, the other two the direction. Samplers that need rejection
// draw further numbers from a generator seeded by these three.
using BsdfSampleInput = std::array<double, 3>;

struct BsdfSample {
    Vec3 wo;
    Rgb weight;        // eval(wi, wo) / pdf(wi, wo); for a delta lobe the lobe's weight
    double pdf = 0;    // solid-angle density; 0 for a delta lobe or an invalid sample
    int lobe = -1;     // model-specific lobe id, -1 when invalid
    bool isDelta = false;

    bool valid() const { return lobe >= 0; }
};

}  // namespace weft
