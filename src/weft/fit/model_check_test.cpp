// The dual-scattering baseline's check (model_check.h) on an RDM made from
// the baseline itself: its single-scattering part as R and the rest as M, so
// the errors must be exactly 0 (a swapped or misplaced part would not be),
// and an all-zero neural model must be 100 % off.
#include "weft/fit/model_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "weft/yarn/dual_scattering.h"
#include "weft/yarn/yarn_model.h"

namespace weft {
namespace {

TEST(DualBaselineCheck, ItsOwnMapsAsTheRdmGiveZeroErrors) {
    const YarnModel model =
        loadYarnModel(std::string(WEFT_SOURCE_DIR) + "/tests/data/fleece-small.json");
    const DualScatteringBsdf dual(model.fiber, model.ply);
    RdmData rdm;
    rdm.bins = RdmBins{4, 8, 6, 12};
    const size_t nIn = rdm.bins.incidentCount(), nOut = rdm.bins.outgoingCount();
    rdm.count.assign(nIn, 5000);
    rdm.pT.assign(nIn, 0.0);
    rdm.rdmR.resize(nIn * nOut * 3);
    rdm.rdmM.resize(nIn * nOut * 3);
    for (size_t i = 0; i < nIn; ++i)
        for (size_t o = 0; o < nOut; ++o) {
            const DualScatteringBsdf::Parts p =
                dual.parts(rdm.bins.incidentCentre(i), rdm.bins.outgoingCentre(o));
            for (int c = 0; c < 3; ++c) {
                rdm.rdmR[(i * nOut + o) * 3 + c] = static_cast<float>(p.single[c]);
                rdm.rdmM[(i * nOut + o) * 3 + c] = static_cast<float>(p.multiple[c]);
            }
        }
    const std::vector<float> zeros(nIn * nOut * 3, 0.0f);
    const nlohmann::json j = checkDualBaseline(model, rdm, zeros, zeros, 1000);
    EXPECT_EQ(j.at("r_rel_l2").get<double>(), 0.0);
    EXPECT_EQ(j.at("m_rel_l2").get<double>(), 0.0);
    EXPECT_EQ(j.at("total_rel_l2").get<double>(), 0.0);
    EXPECT_DOUBLE_EQ(j.at("neural_total_rel_l2").get<double>(), 1.0);
    EXPECT_EQ(j.at("bins_checked").get<size_t>(), nIn);
    // The albedo by quadrature against the RDM's sum over 6 x 12 outgoing
    // bin centres: the same quantity, up to that coarse sum's error.
    for (int c = 0; c < 3; ++c) {
        const double model = j.at("albedo").at("model_mean")[c].get<double>();
        const double sum = j.at("albedo").at("rdm_mean")[c].get<double>();
        EXPECT_TRUE(std::isfinite(model) && model > 0) << c;
        EXPECT_NEAR(model / sum, 1.0, 0.25) << c;
    }
}

}  // namespace
}  // namespace weft
