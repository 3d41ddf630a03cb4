#include "weft/fit/fit.h"

#include <gtest/gtest.h>

#include <cmath>

#include "weft/core/math.h"
#include "weft/core/test_util.h"
#include "weft/fit/metrics.h"
#include "weft/yarn/material_preset.h"
#include "weft/yarn/yarn_lobes.h"

namespace weft {
namespace {

// Fine grid equal to the coarse error grid: the metric is then a plain
// solid-angle-weighted relative L2 over bins, and the tests stay fast.
const RdmBins kBins = kCoarseErrorBins;

const MaterialPreset& fleece() { return findMaterialPreset("fleece"); }

// An RDM-shaped data set made from known functions instead of a gather.
RdmData syntheticRdm(const RdmBins& bins = kBins) {
    RdmData rdm;
    rdm.dir = "synthetic";
    rdm.bins = bins;
    rdm.meta = {{"fiber", fleece().fiber.toJson()},
                {"ply",
                 {{"fibers", fleece().ply.fibers},
                  {"density", fleece().ply.density},
                  {"twist", fleece().ply.twist}}},
                {"paths", 0}};
    const size_t nIn = bins.incidentCount(), nOut = bins.outgoingCount();
    rdm.count.assign(nIn, 1000);
    rdm.pT.assign(nIn, 0.0);
    rdm.rdmR.assign(nIn * nOut * 3, 0.0f);
    rdm.rdmM.assign(nIn * nOut * 3, 0.0f);
    return rdm;
}

FitConfig smallConfig() {
    FitConfig c;
    c.t = {{7, 7}, 6000, 2, 256, 2e-2, 1e-4, Loss::Mse};
    c.m = {{16, 16}, 6000, 1, 256, 1e-2, 1e-4, Loss::Mse};
    c.jitter = false;
    c.threads = 2;
    return c;
}

// Recovering known networks (issue 5): targets from random "teacher" networks
// of the same input layout; the fit must reproduce them almost exactly.
TEST(Fit, RecoversKnownNetworks) {
    RdmData rdm = syntheticRdm();
    const Mlp<float> teacherT({3, 5, 1}, OutputFunction::Sigmoid, 11);
    const Mlp<float> teacherM({6, 6, 3}, OutputFunction::Exp, 12);
    YarnModel teacher;
    teacher.tNet = teacherT.weights();
    teacher.mNet = teacherM.weights();
    rdm.pT = modelTransmissionMap(teacher, kBins);
    rdm.rdmM = modelMultipleScatteringMap(teacher, kBins);
    const FitResult fit = fitYarnModel(rdm, smallConfig(), 3, true);
    EXPECT_LT(fit.report.tRmse, 0.01);
    EXPECT_LT(fit.report.mRelL2, 0.03);
    // Far from the starting point: the untrained student is way off.
    YarnModel untrained;
    untrained.mNet = Mlp<float>({6, 16, 16, 3}, OutputFunction::Exp, 3).weights();
    EXPECT_GT(coarseRelativeL2(modelMultipleScatteringMap(untrained, kBins), rdm.rdmM, kBins),
              0.15);
}

// A model with exit offsets (docs/exit-point.md) fits its M lobe to M in the
// exit frame (rdm_m_exit.npy), not the entry frame's RDM_M: two teachers,
// one per frame; the student follows the exit frame's.
TEST(Fit, ExitOffsetModelsFitMInTheExitFrame) {
    RdmData rdm = syntheticRdm();
    YarnModel entry, exit;
    entry.mNet = Mlp<float>({6, 6, 3}, OutputFunction::Exp, 12).weights();
    exit.mNet = Mlp<float>({6, 6, 3}, OutputFunction::Exp, 13).weights();
    rdm.rdmM = modelMultipleScatteringMap(entry, kBins);
    rdm.rdmMExit = modelMultipleScatteringMap(exit, kBins);
    rdm.exitOffset.assign(kExitOffsetCells * kExitOffsetSlots * 3, 0.0);
    for (size_t cell = 0; cell < kExitOffsetCells; ++cell)
        for (int c = 0; c < 3; ++c) rdm.exitOffset[(cell * kExitOffsetSlots + 4160) * 3 + c] = 0.1;
    FitConfig config = smallConfig();
    config.exitOffset = true;
    const FitResult fit = fitYarnModel(rdm, config, 3, true);
    ASSERT_TRUE(fit.model.exitOffset.has_value());
    const std::vector<float> student = modelMultipleScatteringMap(fit.model, kBins);
    EXPECT_LT(coarseRelativeL2(student, rdm.rdmMExit, kBins), 0.03);
    EXPECT_GT(coarseRelativeL2(student, rdm.rdmM, kBins), 0.15);
    EXPECT_EQ(fit.report.mRelL2, coarseRelativeL2(student, rdm.rdmMExit, kBins));
    // fitTarget: what each model is measured against.
    EXPECT_EQ(fitTarget(rdm, fit.model).rdmM, rdm.rdmMExit);
    EXPECT_EQ(fitTarget(rdm, YarnModel{}).rdmM, rdm.rdmM);
    // Without the exit frame's RDM: an error before any training.
    rdm.rdmMExit.clear();
    testing::expectInputError([&] { fitYarnModel(rdm, config, 3, true); },
                              {"synthetic", "rdm_m_exit.npy", "gather again"});
}

// A target that is exactly eq. 8 times a masking term of the model's form:
// least squares must return its coefficients.
TEST(Fit, MaskingTermIsRecovered) {
    YarnModel model;
    model.fiber = fleece().fiber;
    model.tNet = Mlp<float>({3, 2, 1}, OutputFunction::Sigmoid, 1).weights();
    model.rLobe.tiltDeg = SurfaceFiberFrame::tiltDegOfTwist(0.24);
    const std::vector<float> eq8 = modelReflectionMap(model, kBins);
    model.rLobe.masking = {0.3, 0.25, -0.1, 0.05};
    const std::vector<float> masked = modelReflectionMap(model, kBins);
    const std::vector<double> c = fitMaskingCoefficients(eq8, masked, kBins);
    ASSERT_EQ(c.size(), 4u);
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(c[k], model.rLobe.masking[k], 2e-3) << k;
    EXPECT_GT(coarseRelativeL2(eq8, masked, kBins), 0.3);  // the term matters
}

// A multiple-scattering map proportional to the sampling density itself: the
// fitted lobe parameters must be the ones that made it (second moment 1).
TEST(Fit, SamplingLobeRecoversItsOwnDensity) {
    YarnModel model;
    model.fiber = fleece().fiber;
    model.rLobe.tiltDeg = SurfaceFiberFrame::tiltDegOfTwist(0.24);
    const SamplingParams truth{0.3, 18.0, 35.0, 0.7};
    const SamplingLobes lobes(model.fiber, model.rLobe.tiltDeg, truth);
    const size_t nIn = kBins.incidentCount(), nOut = kBins.outgoingCount();
    std::vector<float> map(nIn * nOut * 3);
    for (size_t i = 0; i < nIn; ++i)
        for (size_t o = 0; o < nOut; ++o)
            for (int c = 0; c < 3; ++c)
                map[(i * nOut + o) * 3 + c] = static_cast<float>(
                    (0.5 + 0.2 * c) * lobes.pdfM(kBins.incidentCentre(i), kBins.outgoingCentre(o)));
    double secondMoment = 0;
    const SamplingParams fit = fitSamplingLobe(model, map, kBins, 0.3, &secondMoment);
    EXPECT_NEAR(fit.betaMDeg, truth.betaMDeg, 1.0);
    EXPECT_NEAR(fit.gammaMDeg, truth.gammaMDeg, 2.0);
    EXPECT_NEAR(fit.kappaM, truth.kappaM, 0.03);
    EXPECT_DOUBLE_EQ(fit.kappaR, 0.3);
    // Discretised on bins, f/pdf is not exactly constant, but close to it.
    EXPECT_LT(secondMoment, 1.02);
    EXPECT_GE(secondMoment, 0.98);
}

// The result depends on the seed, not on the thread count.
TEST(Fit, DeterministicForAnyThreadCount) {
    const RdmBins bins{6, 12, 8, 16};
    RdmData rdm = syntheticRdm(bins);
    YarnModel teacher;
    teacher.tNet = Mlp<float>({3, 4, 1}, OutputFunction::Sigmoid, 5).weights();
    teacher.mNet = Mlp<float>({6, 4, 3}, OutputFunction::Exp, 6).weights();
    rdm.pT = modelTransmissionMap(teacher, bins);
    rdm.rdmM = modelMultipleScatteringMap(teacher, bins);
    FitConfig config = smallConfig();
    config.t.steps = config.m.steps = 300;
    config.jitter = true;
    config.threads = 1;
    const FitResult one = fitYarnModel(rdm, config, 9, true);
    config.threads = 3;
    const FitResult three = fitYarnModel(rdm, config, 9, true);
    EXPECT_TRUE(one.model.tNet == three.model.tNet);
    EXPECT_TRUE(one.model.mNet == three.model.mNet);
    EXPECT_EQ(one.model.rLobe.masking, three.model.rLobe.masking);
    EXPECT_EQ(one.model.sampling.betaMDeg, three.model.sampling.betaMDeg);
    const FitResult other = fitYarnModel(rdm, config, 10, true);
    EXPECT_FALSE(one.model.mNet == other.model.mNet);
}

}  // namespace
}  // namespace weft
