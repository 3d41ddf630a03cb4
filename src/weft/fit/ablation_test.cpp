// The training targets of the ablated models (paper Fig. 5) and the model
// file's "ablation" key.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "weft/core/error.h"
#include "weft/core/math.h"
#include "weft/core/rng.h"
#include "weft/fit/fit.h"
#include "weft/yarn/yarn_model.h"

namespace weft {
namespace {

// A small RDM with random maps and P(T) (not a gather: the targets are pure bookkeeping).
RdmData syntheticRdm() {
    RdmData rdm;
    rdm.dir = "synthetic";
    rdm.bins = {5, 8, 9, 16};
    const size_t nIn = rdm.bins.incidentCount(), nOut = rdm.bins.outgoingCount();
    Rng rng(1, 2);
    rdm.count.assign(nIn, 1000);
    for (size_t i = 0; i < nIn; ++i) rdm.pT.push_back(0.05 + rng.uniform() * 0.45);
    for (size_t k = 0; k < nIn * nOut * 3; ++k) {
        rdm.rdmR.push_back(static_cast<float>(rng.uniform() * 0.2));
        rdm.rdmM.push_back(static_cast<float>(rng.uniform() * 0.1));
    }
    return rdm;
}

TEST(AblationTarget, NaiveIntegratesToTheWholeAlbedo) {
    const RdmData rdm = syntheticRdm();
    const RdmData target = ablationTarget(rdm, YarnAblation::Naive);
    const RdmBins& bins = rdm.bins;
    const size_t nOut = bins.outgoingCount();
    for (size_t i = 0; i < bins.incidentCount(); ++i) {
        EXPECT_EQ(target.pT[i], 0.0);
        for (int c = 0; c < 3; ++c) {
            // Independent sums: the gather's P(T) + E_R + E_M against the target's integral.
            double eR = 0, eM = 0, eTarget = 0;
            for (size_t o = 0; o < nOut; ++o) {
                const size_t k = (i * nOut + o) * 3 + c;
                const double omega = bins.outgoingSolidAngle(o);
                eR += rdm.rdmR[k] * omega;
                eM += rdm.rdmM[k] * omega;
                eTarget += target.rdmM[k] * omega;
                EXPECT_EQ(target.rdmR[k], 0.0f);
            }
            EXPECT_NEAR(eTarget, rdm.pT[i] + eR + eM, 1e-5 * eTarget) << "bin " << i;
        }
        // T sits in exactly one outgoing bin, the one around -wi, grey.
        int extraBins = 0;
        for (size_t o = 0; o < nOut; ++o) {
            const size_t k = (i * nOut + o) * 3;
            const double extra = target.rdmM[k] - (rdm.rdmR[k] + rdm.rdmM[k]);
            if (std::fabs(extra) < 1e-6) continue;
            ++extraBins;
            EXPECT_NEAR(extra, rdm.pT[i] / bins.outgoingSolidAngle(o), 1e-5 * extra);
            EXPECT_NEAR(target.rdmM[k + 1] - (rdm.rdmR[k + 1] + rdm.rdmM[k + 1]), extra,
                        1e-5 * extra);
            // Within a bin's diagonal of -wi (bins of 20 x 22.5 degrees).
            EXPECT_GT(dot(bins.outgoingCentre(o), -bins.incidentCentre(i)), std::cos(radians(25)));
        }
        EXPECT_EQ(extraBins, 1) << "bin " << i;
    }
}

TEST(AblationTarget, NoRLobeAddsRToM) {
    const RdmData rdm = syntheticRdm();
    const RdmData target = ablationTarget(rdm, YarnAblation::NoRLobe);
    EXPECT_EQ(target.pT, rdm.pT);
    EXPECT_EQ(target.count, rdm.count);
    for (size_t k = 0; k < rdm.rdmM.size(); ++k) {
        EXPECT_EQ(target.rdmM[k], rdm.rdmR[k] + rdm.rdmM[k]);
        EXPECT_EQ(target.rdmR[k], 0.0f);
    }
    const RdmData same = ablationTarget(rdm, YarnAblation::None);
    EXPECT_EQ(same.rdmM, rdm.rdmM);
    EXPECT_EQ(same.rdmR, rdm.rdmR);
}

TEST(AblationTarget, TransmissionBinHoldsMinusWi) {
    const RdmBins bins;  // the paper's 22 x 90 x 45 x 90
    for (size_t i = 0; i < bins.incidentCount(); i += 37) {
        const Vec3 wi = bins.incidentCentre(i);
        const size_t o = transmissionOutgoingBin(bins, i);
        EXPECT_EQ(o, bins.outgoingBin(-wi));
        EXPECT_GT(dot(bins.outgoingCentre(o), -wi), std::cos(radians(4)));
    }
}

// ------------------------------------------------------------ model file --

const YarnModel& fleece() {
    static const YarnModel model =
        loadYarnModel(std::string(WEFT_SOURCE_DIR) + "/tests/data/fleece-small.json");
    return model;
}

TEST(YarnModelAblation, KeyIsWrittenReadAndAbsentForTheFullModel) {
    EXPECT_FALSE(yarnModelToJson(fleece()).contains("ablation"));
    EXPECT_EQ(fleece().ablation, YarnAblation::None);
    for (YarnAblation a : {YarnAblation::Naive, YarnAblation::NoRLobe}) {
        YarnModel model = fleece();
        model.ablation = a;
        const nlohmann::json j = yarnModelToJson(model);
        EXPECT_EQ(j.at("ablation"), yarnAblationName(a));
        EXPECT_EQ(yarnModelFromJson(j, "m.json").ablation, a);
    }
    EXPECT_TRUE(YarnModel{}.hasReflectionLobe());
    YarnModel naive;
    naive.ablation = YarnAblation::Naive;
    EXPECT_FALSE(naive.hasTransmissionLobe());
    EXPECT_FALSE(naive.hasReflectionLobe());
    YarnModel noR;
    noR.ablation = YarnAblation::NoRLobe;
    EXPECT_TRUE(noR.hasTransmissionLobe());
    EXPECT_FALSE(noR.hasReflectionLobe());
}

TEST(YarnModelAblation, UnknownValueIsNamed) {
    for (const nlohmann::json& bad : {nlohmann::json("no-r-lobe"), nlohmann::json(3)}) {
        nlohmann::json j = yarnModelToJson(fleece());
        j["ablation"] = bad;
        try {
            yarnModelFromJson(j, "bad.json");
            ADD_FAILURE() << "expected an InputError for " << bad;
        } catch (const InputError& e) {
            const std::string what = e.what();
            for (const char* part : {"bad.json", "ablation", "naive", "no_r_lobe"})
                EXPECT_NE(what.find(part), std::string::npos) << what;
        }
    }
}

// The model maps of an ablated model: its missing parts are zero.
TEST(YarnModelAblation, ModelMapsLeaveOutTheMissingParts) {
    const RdmBins bins{3, 4, 5, 8};
    YarnModel naive = fleece();
    naive.ablation = YarnAblation::Naive;
    for (double pT : modelTransmissionMap(naive, bins)) EXPECT_EQ(pT, 0.0);
    YarnModel noR = fleece();
    noR.ablation = YarnAblation::NoRLobe;
    EXPECT_EQ(modelTransmissionMap(noR, bins), modelTransmissionMap(fleece(), bins));
    for (float r : modelReflectionMap(noR, bins)) EXPECT_EQ(r, 0.0f);
    double fullR = 0;
    for (float r : modelReflectionMap(fleece(), bins)) fullR += r;
    EXPECT_GT(fullR, 0.0);
    EXPECT_EQ(modelMultipleScatteringMap(noR, bins), modelMultipleScatteringMap(fleece(), bins));
}

}  // namespace
}  // namespace weft
