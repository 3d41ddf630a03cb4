// The yarn BSDF of ablated models (naive, no R lobe) and with cosine
// sampling: the ablations of paper Fig. 5 (docs/fit.md, docs/yarn.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "weft/core/chi2.h"
#include "weft/core/error.h"
#include "weft/core/math.h"
#include "weft/core/test_util.h"
#include "weft/yarn/yarn_bsdf.h"
#include "weft/yarn/yarn_integrals.h"
#include "weft/yarn/yarn_test_util.h"

namespace weft {
namespace {

const YarnModel& fleece() {
    static const YarnModel model =
        loadYarnModel(std::string(WEFT_SOURCE_DIR) + "/tests/data/fleece-small.json");
    return model;
}

YarnModel ablated(YarnAblation ablation) {
    YarnModel model = fleece();
    model.ablation = ablation;
    return model;
}

Vec3 randomUnitVector(Rng& rng) {
    const double z = 1 - 2 * rng.uniform(), phi = kTwoPi * rng.uniform();
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
}

// Normal, oblique, grazing (where P(T) is large) and below the surface.
const Vec3 kIncident[] = {
    sphericalDirection(radians(3), radians(20)), sphericalDirection(radians(45), radians(-60)),
    sphericalDirection(radians(87), radians(100)), sphericalDirection(radians(120), radians(30))};

// Lobe counts of `n` samples at random incident directions, checking weight == eval / pdf.
std::vector<int> sampleLobes(const YarnBsdf& bsdf, int n) {
    std::vector<int> counts(3, 0);
    Rng rng(3, 4);
    for (int k = 0; k < n; ++k) {
        const Vec3 wi = randomUnitVector(rng);
        const BsdfSample s = bsdf.sample(wi, {rng.uniform(), rng.uniform(), rng.uniform()});
        if (!s.valid()) continue;
        ++counts[static_cast<size_t>(s.lobe)];
        if (s.isDelta) continue;
        const Rgb f = bsdf.eval(wi, s.wo);
        const double pdf = bsdf.pdf(wi, s.wo);
        EXPECT_NEAR(s.pdf, pdf, 1e-12 * pdf);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.weight[c], f[c] / pdf, 1e-12 * (f[c] / pdf));
    }
    return counts;
}

TEST(YarnBsdfAblation, NaiveHasNoTransmissionAndNoReflection) {
    // Cosine sampling: the lobes are the evaluator's, and its table would be
    // the slowest part of the test (about a minute under the sanitizers).
    const YarnBsdfOptions cosine{true, YarnSampling::Cosine};
    const YarnBsdf full(fleece(), "fleece-small.json", cosine);
    const YarnBsdf naive(ablated(YarnAblation::Naive), "naive", cosine);
    EXPECT_EQ(naive.ablation(), YarnAblation::Naive);
    Rng rng(1, 2);
    int transmitting = 0;
    for (int k = 0; k < 2000; ++k) {
        const Vec3 wi = randomUnitVector(rng), wo = randomUnitVector(rng);
        transmitting += full.transmission(wi) > 0.01;
        ASSERT_EQ(naive.transmission(wi), 0.0);
        const YarnComponents c = naive.components(wi, wo);
        EXPECT_EQ(c.pT, 0.0);
        EXPECT_TRUE(c.r.isBlack());
        EXPECT_EQ(naive.eval(wi, wo), c.m);
        const YarnLobeProbabilities p = naive.lobeProbabilities(wi);
        EXPECT_EQ(p.t, 0.0);
        EXPECT_EQ(p.r, 0.0);
        EXPECT_EQ(p.m, 1.0);
    }
    EXPECT_GT(transmitting, 20) << "the full model must transmit somewhere, or this proves nothing";
    const std::vector<int> lobes = sampleLobes(naive, 20000);
    EXPECT_EQ(lobes[YarnBsdf::kLobeT], 0);
    EXPECT_EQ(lobes[YarnBsdf::kLobeR], 0);
    EXPECT_GT(lobes[YarnBsdf::kLobeM], 19000);
}

TEST(YarnBsdfAblation, NoRLobeEvaluatesTheNetworkAlone) {
    // Without calibration and energy guard eval is exactly exp(M network).
    YarnModel model = ablated(YarnAblation::NoRLobe);
    model.calibration = EnergyCalibration{};
    YarnBsdfOptions options;
    options.energyGuard = false;
    options.sampling = YarnSampling::Cosine;  // eval alone: no sampling table to build
    const YarnBsdf bsdf(model, "no-r", options);
    const ScatteringMlp mNet(model.mNet, "m_net");
    Rng rng(5, 6);
    for (int k = 0; k < 500; ++k) {
        Vec3 wi = randomUnitVector(rng);
        wi.z = std::fabs(wi.z);
        const Vec3 wo = randomUnitVector(rng);
        const Rgb y = evalScattering(mNet, wi, wo);
        const Rgb f = bsdf.eval(wi, wo);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(f[c], y[c], 1e-5 * y[c]) << wi << " " << wo;
        EXPECT_TRUE(bsdf.components(wi, wo).r.isBlack());
    }
    // With both (the model as rendered): still no R, and T as in the full model.
    const YarnBsdf guarded(ablated(YarnAblation::NoRLobe), "no-r");
    const YarnBsdf full(fleece(), "fleece-small.json");
    for (const Vec3& wi : kIncident) {
        EXPECT_EQ(guarded.transmission(wi), full.transmission(wi));
        EXPECT_EQ(guarded.lobeProbabilities(wi).r, 0.0);
        const DirectionalIntegrals e = integrateDirections(guarded, wi);
        EXPECT_TRUE(e.r.isBlack());
        for (int c = 0; c < 3; ++c) EXPECT_LE(e.albedo()[c], 1.0 + 1e-2) << "energy guard, " << wi;
    }
    const std::vector<int> lobes = sampleLobes(guarded, 20000);
    EXPECT_EQ(lobes[YarnBsdf::kLobeR], 0);
    EXPECT_GT(lobes[YarnBsdf::kLobeT], 0);
    EXPECT_GT(lobes[YarnBsdf::kLobeM], 0);
}

TEST(YarnBsdfAblation, SamplingNamesAreParsed) {
    EXPECT_EQ(parseYarnSampling("fitted", "--yarn-sampling"), YarnSampling::Fitted);
    EXPECT_EQ(parseYarnSampling("cosine", "--yarn-sampling"), YarnSampling::Cosine);
    try {
        parseYarnSampling("x", "--yarn-sampling");
        ADD_FAILURE() << "expected an InputError";
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("--yarn-sampling"), std::string::npos) << what;
        EXPECT_NE(what.find("fitted, cosine"), std::string::npos) << what;
    }
}

YarnBsdf cosineBsdf(const YarnModel& model) {
    YarnBsdfOptions options;
    options.sampling = YarnSampling::Cosine;
    return YarnBsdf(model, "cosine", options);
}

TEST(YarnBsdfCosineSampling, PdfIntegratesToOneMinusTransmission) {
    const YarnBsdf bsdf = cosineBsdf(fleece());
    for (const Vec3& wi : kIncident) {
        const SphereRule rule = yarnSphereRule(bsdf, wi, 1);
        double integral = 0;
        for (size_t k = 0; k < rule.directions.size(); ++k)
            integral += bsdf.pdf(wi, rule.directions[k]) * rule.weights[k];
        EXPECT_NEAR(integral, 1 - bsdf.transmission(wi), 1e-6) << wi;
        // The density is the cosine one, whatever the fitted lobes say.
        const Vec3 wo = sphericalDirection(radians(130), radians(10));
        EXPECT_NEAR(bsdf.pdf(wi, wo), (1 - bsdf.transmission(wi)) * std::fabs(wo.z) / kTwoPi,
                    1e-15);
    }
}

TEST(YarnBsdfCosineSampling, WeightIsEvalOverPdfAndTStaysADelta) {
    const YarnBsdf bsdf = cosineBsdf(fleece());
    const YarnBsdf fitted(fleece(), "fleece-small.json",
                          YarnBsdfOptions{true, YarnSampling::Fitted});
    const std::vector<int> lobes = sampleLobes(bsdf, 20000);
    EXPECT_EQ(lobes[YarnBsdf::kLobeR], 0);
    EXPECT_GT(lobes[YarnBsdf::kLobeT], 0);
    Rng rng(9, 10);
    for (int k = 0; k < 2000; ++k) {
        const Vec3 wi = randomUnitVector(rng);
        const double pT = bsdf.transmission(wi);
        EXPECT_EQ(pT, fitted.transmission(wi));
        // The same u[0] below P(T) picks the same delta as the fitted sampler.
        const BsdfSampleInput u = {pT * rng.uniform(), rng.uniform(), rng.uniform()};
        if (!(pT > 0)) continue;
        const BsdfSample a = bsdf.sample(wi, u), b = fitted.sample(wi, u);
        EXPECT_TRUE(a.isDelta);
        EXPECT_EQ(a.wo, b.wo);
        EXPECT_EQ(a.weight, b.weight);
        // eval does not depend on the sampling.
        const Vec3 wo = randomUnitVector(rng);
        EXPECT_EQ(bsdf.eval(wi, wo), fitted.eval(wi, wo));
    }
}

TEST(YarnBsdfCosineSampling, SamplingIsChiSquareConsistentWithPdf) {
    const YarnBsdf full = cosineBsdf(fleece());
    const YarnBsdf naive = cosineBsdf(ablated(YarnAblation::Naive));
    const int tests = 2 * static_cast<int>(std::size(kIncident));
    const double alpha = sidakCorrectedLevel(0.01, tests);
    const SphereGrid grid{40, 80};
    for (const YarnBsdf* bsdf : {&full, &naive}) {
        for (const Vec3& wi : kIncident) {
            // In the yarn frame; the delta lobe is one more cell (P_T = P(T|wi) here).
            ASSERT_EQ(bsdf->lobeProbabilities(wi).t, bsdf->transmission(wi));
            const Chi2Result r =
                testing::yarnSamplingChi2(*bsdf, wi, grid, testing::scaled(200000), 11, false);
            std::printf("  %s, wi %s: chi2 %.1f, dof %d, p %.3g\n",
                        bsdf == &full ? "full" : "naive",
                        (std::ostringstream() << wi).str().c_str(), r.statistic, r.dof, r.pValue);
            EXPECT_GT(r.pValue, alpha) << wi << ": chi2 = " << r.statistic << ", dof = " << r.dof;
        }
    }
}

}  // namespace
}  // namespace weft
