#include "weft/fit/metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "weft/core/math.h"
#include "weft/core/rng.h"

namespace weft {
namespace {

std::vector<float> randomMap(const RdmBins& bins, uint64_t seed) {
    Rng rng(seed, 1);
    std::vector<float> m(bins.incidentCount() * bins.outgoingCount() * 3);
    for (float& v : m) v = static_cast<float>(rng.uniform());
    return m;
}

TEST(Metrics, ZeroForIdenticalMapsAndExactForAUniformScale) {
    const RdmBins fine{22, 90, 45, 90};
    const std::vector<float> ref = randomMap(fine, 1);
    EXPECT_EQ(coarseRelativeL2(ref, ref, fine), 0.0);
    std::vector<float> scaled = ref;
    for (float& v : scaled) v *= 1.25f;
    EXPECT_NEAR(coarseRelativeL2(scaled, ref, fine), 0.25, 1e-6);
}

TEST(Metrics, PoolingConservesOutgoingEnergy) {
    // Sum over coarse outgoing bins of P W_O equals the mean, over the fine
    // incident bins of the coarse bin, of sum_o v W_o.
    const RdmBins fine{22, 90, 45, 90}, coarse = kCoarseErrorBins;
    const std::vector<float> map = randomMap(fine, 2);
    const std::vector<double> pooled = poolRdm(map, fine, coarse);
    const size_t nOut = fine.outgoingCount(), cOut = coarse.outgoingCount();
    for (size_t I : {size_t{0}, size_t{17}, coarse.incidentCount() - 1}) {
        double coarseEnergy = 0, fineEnergy = 0;
        int members = 0;
        for (size_t O = 0; O < cOut; ++O)
            coarseEnergy += pooled[(I * cOut + O) * 3 + 1] * coarse.outgoingSolidAngle(O);
        for (size_t i = 0; i < fine.incidentCount(); ++i) {
            if (coarse.incidentBin(fine.incidentCentre(i)) != I) continue;
            ++members;
            for (size_t o = 0; o < nOut; ++o)
                fineEnergy += map[(i * nOut + o) * 3 + 1] * fine.outgoingSolidAngle(o);
        }
        EXPECT_EQ(members, 4);  // 22x90 -> 11x45 incident bins
        EXPECT_NEAR(coarseEnergy, fineEnergy / members, 1e-9 * fineEnergy);
    }
}

TEST(Metrics, HandComputedTwoByTwoCase) {
    // Fine: 1 incident bin, theta_o in two halves (upper, lower), one phi bin.
    // Coarse: one outgoing bin. Upper and lower hemispheres have equal solid
    // angle 2 pi, so the pooled value is the plain mean of the two values.
    const RdmBins fine{1, 1, 2, 1}, coarse{1, 1, 1, 1};
    const std::vector<float> ref = {1, 2, 3, 3, 4, 5}, fit = {1, 2, 3, 5, 4, 3};
    const std::vector<double> pooled = poolRdm(ref, fine, coarse);
    EXPECT_NEAR(pooled[0], 2.0, 1e-12);
    EXPECT_NEAR(pooled[1], 3.0, 1e-12);
    EXPECT_NEAR(pooled[2], 4.0, 1e-12);
    // fit pools to (3, 3, 3): error sqrt((1 + 0 + 1) / (4 + 9 + 16)).
    EXPECT_NEAR(coarseRelativeL2(fit, ref, fine, coarse), std::sqrt(2.0 / 29.0), 1e-12);
}

TEST(Metrics, FineScaleNoiseAveragesOut) {
    // Noise with zero sum over the three fine phi bins (equal solid angles) of
    // each coarse phi bin cancels in the pooled comparison, not in a fine one.
    const RdmBins fine{22, 90, 45, 90};
    const std::vector<float> ref(fine.incidentCount() * fine.outgoingCount() * 3, 1.0f);
    std::vector<float> noisy = ref;
    for (size_t k = 0; k < noisy.size(); ++k) noisy[k] += ((k / 3) % 3 == 0 ? 0.5f : -0.25f);
    EXPECT_LT(coarseRelativeL2(noisy, ref, fine), 1e-6);
    EXPECT_NEAR(coarseRelativeL2(noisy, ref, fine, fine), std::sqrt(0.125), 1e-6);
}

}  // namespace
}  // namespace weft
