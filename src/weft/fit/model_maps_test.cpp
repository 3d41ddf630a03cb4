#include "weft/fit/model_maps.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "weft/yarn/yarn_bsdf.h"
#include "weft/yarn/yarn_test_util.h"

namespace weft {
namespace {

const char* const kModels[] = {"fleece-small", "gabardine-small"};

YarnModel testModel(const std::string& name) { return loadYarnModel(testing::testModelPath(name)); }
using testing::withCalibration;

// The maps evaluate the model's parts on their own (model_maps.h): they must
// agree with the renderer's BSDF without the energy guard.
TEST(ModelMaps, MatchTheYarnBsdfComponents) {
    const RdmBins bins{3, 5, 6, 8};
    for (const char* name : kModels)
        for (const YarnModel& model : {testModel(name), withCalibration(testModel(name))}) {
            const YarnBsdf bsdf(model, name, YarnBsdfOptions{false});
            const std::vector<double> pT = modelTransmissionMap(model, bins);
            const std::vector<float> r = modelReflectionMap(model, bins);
            const std::vector<float> m = modelMultipleScatteringMap(model, bins);
            for (size_t i = 0; i < bins.incidentCount(); ++i) {
                const Vec3 wi = bins.incidentCentre(i);
                EXPECT_NEAR(bsdf.transmission(wi), pT[i], 1e-6);
                for (size_t o = 0; o < bins.outgoingCount(); ++o) {
                    const YarnComponents c = bsdf.components(wi, bins.outgoingCentre(o));
                    for (int k = 0; k < 3; ++k) {
                        const size_t index = (i * bins.outgoingCount() + o) * 3 + k;
                        EXPECT_NEAR(c.m[k], m[index], 1e-5 * m[index]);
                        EXPECT_NEAR(c.r[k], r[index], 1e-5 * r[index] + 1e-7);
                    }
                }
            }
        }
}

}  // namespace
}  // namespace weft
