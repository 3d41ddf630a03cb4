#include "weft/yarn/yarn_bsdf.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "weft/core/chi2.h"
#include "weft/core/file.h"
#include "weft/core/math.h"
#include "weft/core/test_util.h"
#include "weft/yarn/energy_guard.h"
#include "weft/yarn/material_preset.h"
#include "weft/yarn/yarn_integrals.h"
#include "weft/yarn/yarn_test_util.h"

namespace weft {
namespace {

// Models fitted by the pipeline (tests/data/README.md gives the commands).
const char* const kModels[] = {"fleece-small", "gabardine-small"};

// Every model, or the first alone under the sanitizers (where building a
// yarn BSDF's tables takes most of a minute).
std::vector<const char*> sanitizerSubset(const char* const (&models)[2]) {
    if (testing::sampleScale() < 1) return {models[0]};
    return {models[0], models[1]};
}

std::string modelPath(const std::string& name) {
    return std::string(WEFT_SOURCE_DIR) + "/tests/data/" + name + ".json";
}

const YarnModel& testModel(const std::string& name) {
    static const YarnModel fleece = loadYarnModel(modelPath("fleece-small"));
    static const YarnModel gabardine = loadYarnModel(modelPath("gabardine-small"));
    return name == "fleece-small" ? fleece : gabardine;
}

// Built on first use only (the energy guard's tables take a moment).
const YarnBsdf& testBsdf(const std::string& name) {
    if (name == "fleece-small") {
        static const YarnBsdf fleece(testModel(name), "fleece-small.json");
        return fleece;
    }
    static const YarnBsdf gabardine(testModel("gabardine-small"), "gabardine-small.json");
    return gabardine;
}

// Yarn-frame direction from the polar angle (from n) and azimuth (from t), degrees.
Vec3 yarnDirection(double thetaDeg, double phiDeg) {
    return sphericalDirection(radians(thetaDeg), radians(phiDeg));
}

Vec3 randomUnitVector(Rng& rng) {
    const double z = 1 - 2 * rng.uniform(), phi = kTwoPi * rng.uniform();
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
}

std::string text(const Vec3& v) { return (std::ostringstream() << v).str(); }

// Incident directions of the sampling tests: near normal, oblique, grazing to
// the surface, along the surface fibers, and one below the surface (mirrored).
struct Incident {
    const char* name;
    Vec3 (*direction)(const YarnBsdf&);
};
const Incident kIncident[] = {
    {"normal", [](const YarnBsdf&) { return yarnDirection(3, 20); }},
    {"oblique", [](const YarnBsdf&) { return yarnDirection(45, -60); }},
    {"grazing", [](const YarnBsdf&) { return yarnDirection(87, 100); }},
    {"along the surface fibers",
     [](const YarnBsdf& b) {
         return b.model().frame().fromLocal({std::sin(radians(85)), 0, std::cos(radians(85))});
     }},
    {"below the surface", [](const YarnBsdf&) { return yarnDirection(120, 30); }},
};

// T is picked with probability P_T = lobeProbabilities(wi).t (P(T|wi) for the
// fitted sampler) and weighs P(T|wi) / P_T, grey.
TEST(YarnBsdf, TransmissionIsADeltaOfWeightPOverPick) {
    for (const char* name : kModels) {
        const YarnBsdf fitted(testModel(name), name, YarnBsdfOptions{true, YarnSampling::Fitted});
        for (const YarnBsdf* bsdf : {&testBsdf(name), &fitted}) {
            Rng rng(1, 2);
            int deltas = 0;
            for (int k = 0; k < 2000; ++k) {
                const Vec3 wi = randomUnitVector(rng);
                const double pT = bsdf->transmission(wi);
                const double pick = bsdf->lobeProbabilities(wi).t;
                ASSERT_GE(pT, 0.0);
                ASSERT_LE(pT, 1.0);
                ASSERT_EQ(pick > 0, pT > 0);
                if (bsdf == &fitted) {
                    ASSERT_EQ(pick, pT);
                }
                // u[0] just below P_T picks T: wo is exactly -wi.
                const BsdfSample s = bsdf->sample(wi, {pick * 0.999, rng.uniform(), rng.uniform()});
                if (pT == 0) continue;
                ASSERT_TRUE(s.valid());
                EXPECT_EQ(s.lobe, YarnBsdf::kLobeT);
                EXPECT_TRUE(s.isDelta);
                EXPECT_EQ(s.wo, -wi);
                EXPECT_EQ(s.weight, Rgb(pT / pick));
                if (bsdf == &fitted) {
                    EXPECT_EQ(s.weight, Rgb(1.0));
                }
                EXPECT_EQ(s.pdf, 0.0);
                ++deltas;
            }
            EXPECT_GT(deltas, 1900) << name;
        }
    }
}

TEST(YarnBsdf, SampleWeightIsEvalOverPdf) {
    for (const char* name : kModels) {
        const YarnBsdf& bsdf = testBsdf(name);
        Rng rng(3, 4);
        int counts[3] = {0, 0, 0};
        for (int k = 0; k < 20000; ++k) {
            const Vec3 wi = randomUnitVector(rng);
            const BsdfSample s = bsdf.sample(wi, {rng.uniform(), rng.uniform(), rng.uniform()});
            ASSERT_TRUE(s.valid()) << wi;
            ++counts[s.lobe];
            if (s.isDelta) continue;
            EXPECT_NEAR(length(s.wo), 1.0, 1e-12);
            const Rgb f = bsdf.eval(wi, s.wo);
            const double pdf = bsdf.pdf(wi, s.wo);
            ASSERT_GT(pdf, 0);
            EXPECT_NEAR(s.pdf, pdf, 1e-12 * pdf);
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(s.weight[c], f[c] / pdf, 1e-12 * (f[c] / pdf) + 1e-300);
            EXPECT_TRUE(s.weight.isFinite());
            EXPECT_LT(s.weight.maxComponent(), 100.0) << "eval / pdf must stay bounded";
        }
        EXPECT_GT(counts[YarnBsdf::kLobeR], 0) << name;
        EXPECT_GT(counts[YarnBsdf::kLobeM], 0) << name;
        std::printf("%s: lobes T %d R %d M %d\n", name, counts[0], counts[1], counts[2]);
    }
}

TEST(YarnBsdf, SamplingIsChiSquareConsistentWithPdf) {
    const int tests = static_cast<int>(2 * std::size(kModels) * std::size(kIncident));
    const double alpha = sidakCorrectedLevel(0.01, tests);
    // Cells in the surface fiber frame, where the R lobe is a band of theta.
    const SphereGrid grid{90, 90};
    double minP = 1;
    for (const char* name : kModels) {
        for (const YarnSampling sampling : {YarnSampling::Tabulated, YarnSampling::Fitted}) {
            const YarnBsdf bsdf(testModel(name), name, YarnBsdfOptions{true, sampling});
            for (const Incident& incident : kIncident) {
                const Vec3 wi = incident.direction(bsdf);
                const Chi2Result r =
                    testing::yarnSamplingChi2(bsdf, wi, grid, testing::scaled(200000), 11, true);
                std::printf("  %s (%s), wi %s: chi2 %.1f, dof %d, p %.3g\n", name,
                            yarnSamplingName(sampling), incident.name, r.statistic, r.dof,
                            r.pValue);
                minP = std::min(minP, r.pValue);
                EXPECT_GT(r.pValue, alpha) << name << ", wi " << incident.name
                                           << ": chi2 = " << r.statistic << ", dof = " << r.dof;
            }
        }
    }
    std::printf("chi-square: %d tests, smallest p-value %.3g (level %.3g)\n", tests, minP, alpha);
}

// The same pair seen from below the surface: both directions mirrored (z -> -z).
TEST(YarnBsdf, LowerHemisphereMirrorsBothDirections) {
    const YarnBsdf& bsdf = testBsdf("fleece-small");
    Rng rng(5, 6);
    for (int k = 0; k < 200; ++k) {
        Vec3 wi = randomUnitVector(rng);
        wi.z = -std::fabs(wi.z);
        const Vec3 wo = randomUnitVector(rng);
        const Vec3 wiUp{wi.x, wi.y, -wi.z}, woUp{wo.x, wo.y, -wo.z};
        EXPECT_EQ(bsdf.eval(wi, wo), bsdf.eval(wiUp, woUp));
        EXPECT_EQ(bsdf.pdf(wi, wo), bsdf.pdf(wiUp, woUp));
        EXPECT_EQ(bsdf.transmission(wi), bsdf.transmission(wiUp));
        const BsdfSampleInput u = {rng.uniform(), rng.uniform(), rng.uniform()};
        const BsdfSample a = bsdf.sample(wi, u), b = bsdf.sample(wiUp, u);
        EXPECT_EQ(a.lobe, b.lobe);
        if (a.isDelta) {
            EXPECT_EQ(a.wo, -wi);
        } else {
            EXPECT_EQ(a.wo, (Vec3{b.wo.x, b.wo.y, -b.wo.z}));
        }
        EXPECT_EQ(a.weight, b.weight);
    }
}

TEST(YarnBsdf, FiniteForEveryDirection) {
    const std::vector<Vec3> special = {{0, 0, 1},
                                       {0, 0, -1},
                                       {1, 0, 0},
                                       {-1, 0, 0},
                                       {0, 1, 0},
                                       {0, -1, 0},
                                       yarnDirection(89.999, 0),
                                       yarnDirection(90, 45),
                                       yarnDirection(90.001, -90),
                                       yarnDirection(1e-9, 10)};
    for (const char* name : kModels) {
        const YarnBsdf& bsdf = testBsdf(name);
        const SurfaceFiberFrame& frame = bsdf.model().frame();
        std::vector<Vec3> dirs = special;
        // Along the surface fibers, exactly and a hair above the surface.
        for (const Vec3& local :
             {Vec3{1, 0, 0}, Vec3{-1, 0, 0}, Vec3{std::sin(1.5707), 0, std::cos(1.5707)}})
            dirs.push_back(frame.fromLocal(local));
        Rng rng(7, 8);
        for (int k = 0; k < 300; ++k) dirs.push_back(randomUnitVector(rng));
        for (const Vec3& wi : dirs) {
            std::vector<Vec3> outgoing = dirs;
            outgoing.push_back(wi);
            outgoing.push_back(-wi);
            outgoing.push_back({wi.x, wi.y, -wi.z});
            for (const Vec3& wo : outgoing) {
                const Rgb f = bsdf.eval(wi, wo);
                ASSERT_TRUE(f.isFinite()) << name << " " << wi << " " << wo;
                ASSERT_GE(std::min({f.r, f.g, f.b}), 0.0);
                const double p = bsdf.pdf(wi, wo);
                ASSERT_TRUE(std::isfinite(p) && p >= 0) << name << " " << wi << " " << wo;
            }
            for (int k = 0; k < 20; ++k) {
                const BsdfSample s = bsdf.sample(wi, {rng.uniform(), rng.uniform(), rng.uniform()});
                if (!s.valid()) continue;
                ASSERT_TRUE(s.weight.isFinite()) << name << " " << wi;
                ASSERT_TRUE(isFinite(s.wo));
            }
        }
    }
}

TEST(YarnBsdf, SampleIsDeterministicInItsInput) {
    const YarnBsdf& bsdf = testBsdf("gabardine-small");
    const Vec3 wi = yarnDirection(30, 40);
    for (double u0 : {0.1, 0.5, 0.95}) {
        const BsdfSample a = bsdf.sample(wi, {u0, 0.6, 0.9}), b = bsdf.sample(wi, {u0, 0.6, 0.9});
        EXPECT_EQ(a.wo, b.wo);
        EXPECT_EQ(a.weight, b.weight);
    }
}

TEST(YarnBsdf, SliceEqualsTheTwoDirectionCalls) {
    // The slice computes what depends on wi once; its eval, pdf, evalPdf and
    // sample must be those of the BSDF, above and below the surface.
    const YarnBsdf& bsdf = testBsdf("fleece-small");
    Rng rng(4, 4);
    for (const Vec3& wi :
         {yarnDirection(30, 40), yarnDirection(85, -120), yarnDirection(130, 10)}) {
        const BsdfSlice slice = bsdf.slice(wi);
        for (int k = 0; k < 50; ++k) {
            const Vec3 wo = yarnDirection(180 * rng.uniform(), 360 * rng.uniform() - 180);
            const BsdfSampleInput u = {rng.uniform(), rng.uniform(), rng.uniform()};
            testing::expectBsdfFormsAgree(bsdf, slice, wo, u, k);
        }
    }
}

TEST(YarnBsdf, InterfaceCallsAgreeExactly) {
    // Through the Bsdf interface, for both models, with and without the
    // energy guard and with cosine sampling: evalPdf is (eval, pdf) bit for
    // bit, and a continuous sample's weight is eval / pdf at its wo, also bit
    // for bit (the sample evaluates the same mirrored pair).
    // One model under the (slow) sanitizers.
    for (const char* name : sanitizerSubset(kModels))
        for (const YarnBsdfOptions options : {YarnBsdfOptions{}, YarnBsdfOptions{false},
                                              YarnBsdfOptions{true, YarnSampling::Cosine}}) {
            const YarnBsdf yarn(testModel(name), name, options);
            const Bsdf& bsdf = yarn;
            Rng rng(6, 6);
            int continuous = 0;
            for (int k = 0; k < 300; ++k) {
                const Vec3 wi = randomUnitVector(rng), wo = randomUnitVector(rng);
                const BsdfEval e = bsdf.evalPdf(wi, wo);
                ASSERT_EQ(e.value, bsdf.eval(wi, wo)) << name << " " << text(wi) << text(wo);
                ASSERT_EQ(e.pdf, bsdf.pdf(wi, wo)) << name << " " << text(wi) << text(wo);
                const BsdfSampleInput u = {rng.uniform(), rng.uniform(), rng.uniform()};
                const BsdfSample s = bsdf.sample(wi, u);
                if (!s.valid() || s.isDelta) continue;
                ++continuous;
                const BsdfEval at = bsdf.evalPdf(wi, s.wo);
                ASSERT_EQ(s.pdf, at.pdf) << name << " " << text(wi);
                ASSERT_EQ(s.weight, at.value / at.pdf) << name << " " << text(wi);
            }
            EXPECT_GT(continuous, 100) << name;
        }
}

TEST(YarnBsdf, DraftWithTabulatedSamplingIsTheTabulatedBsdf) {
    // weft view's draft material (fitted sampling) made final: eval, pdf,
    // the lobe probabilities and samples bit for bit those of a BSDF built
    // with the table, with and without the energy guard; the draft's own
    // density is another one (else the test could not tell them apart).
    for (const char* name : sanitizerSubset(kModels))
        for (const bool guard : {true, false}) {
            const YarnBsdf draft(testModel(name), name,
                                 YarnBsdfOptions{guard, YarnSampling::Fitted});
            const YarnBsdf fresh(testModel(name), name, YarnBsdfOptions{guard});
            const std::unique_ptr<YarnBsdf> finished = draft.withTabulatedSampling();
            EXPECT_EQ(finished->sampling(), YarnSampling::Tabulated);
            EXPECT_EQ(finished->memoryBytes(), fresh.memoryBytes());
            Rng rng(9, 9);
            int pdfsDiffer = 0;
            for (int k = 0; k < 200; ++k) {
                const Vec3 wi = randomUnitVector(rng), wo = randomUnitVector(rng);
                const BsdfEval a = finished->evalPdf(wi, wo), b = fresh.evalPdf(wi, wo);
                ASSERT_EQ(a.value, b.value) << name << " " << text(wi) << text(wo);
                ASSERT_EQ(a.pdf, b.pdf) << name << " " << text(wi) << text(wo);
                ASSERT_EQ(a.value, draft.eval(wi, wo)) << name << " " << text(wi) << text(wo);
                if (draft.pdf(wi, wo) != b.pdf) ++pdfsDiffer;
                const BsdfSampleInput u = {rng.uniform(), rng.uniform(), rng.uniform()};
                const BsdfSample sa = finished->sample(wi, u), sb = fresh.sample(wi, u);
                ASSERT_EQ(sa.wo, sb.wo) << name << " " << text(wi);
                ASSERT_EQ(sa.weight, sb.weight) << name << " " << text(wi);
                const YarnLobeProbabilities pa = finished->lobeProbabilities(wi),
                                            pb = fresh.lobeProbabilities(wi);
                ASSERT_EQ(pa.t, pb.t);
                ASSERT_EQ(pa.r, pb.r);
                ASSERT_EQ(pa.m, pb.m);
            }
            EXPECT_GT(pdfsDiffer, 150) << name;
        }
}

using testing::withCalibration;

TEST(YarnBsdf, EnergyCalibrationScalesTheLobes) {
    const YarnModel& model = testModel("fleece-small");
    YarnModel plain = model;
    plain.calibration = EnergyCalibration{};
    // The fitted sampler, whose density does not depend on the calibration.
    const YarnBsdf a(plain, "plain", YarnBsdfOptions{false, YarnSampling::Fitted});
    const YarnBsdf b(withCalibration(plain), "calibrated",
                     YarnBsdfOptions{false, YarnSampling::Fitted});
    Rng rng(5, 5);
    for (int k = 0; k < 200; ++k) {
        const Vec3 wi = randomUnitVector(rng), wo = randomUnitVector(rng);
        const YarnComponents ca = a.components(wi, wo), cb = b.components(wi, wo);
        const double x = wi.x;  // the mirroring below the surface keeps x
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(cb.r[c], 0.5 * ca.r[c], 1e-12 + 1e-9 * ca.r[c]);
            EXPECT_NEAR(cb.m[c], 2 * std::exp(0.3 * x) * ca.m[c], 1e-6 * cb.m[c]);
        }
        EXPECT_EQ(a.pdf(wi, wo), b.pdf(wi, wo));  // the sampling densities do not move
    }
}

// --------------------------------------------------------- integrals / energy --

TEST(YarnIntegrals, QuadratureConvergedAndPdfIntegratesToOneMinusPickT) {
    for (const char* name : sanitizerSubset(kModels)) {
        const YarnBsdf& bsdf = testBsdf(name);
        for (const Incident& incident : kIncident) {
            const Vec3 wi = incident.direction(bsdf);
            const DirectionalIntegrals a = integrateDirections(bsdf, wi, 1);
            const DirectionalIntegrals b = integrateDirections(bsdf, wi, 3);
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(a.r[c], b.r[c], 2e-3 * b.r[c] + 1e-6) << name << " " << incident.name;
                EXPECT_NEAR(a.m[c], b.m[c], 1e-3 * b.m[c] + 1e-6) << name << " " << incident.name;
            }
            EXPECT_NEAR(a.secondMomentYarn, b.secondMomentYarn, 1e-2 * b.secondMomentYarn);
            const SphereRule rule = yarnSphereRule(bsdf, wi, 1);
            double pdfIntegral = 0;
            for (size_t k = 0; k < rule.directions.size(); ++k)
                pdfIntegral += bsdf.pdf(wi, rule.directions[k]) * rule.weights[k];
            EXPECT_NEAR(pdfIntegral, 1 - bsdf.lobeProbabilities(wi).t, 2e-3)
                << name << " " << incident.name;
        }
    }
}

// The mean sample weight (T included) estimates the directional albedo: the
// sampler is unbiased and the quadrature right, independently of each other.
// The quadrature's weight statistics (what `weft yarn check` reports per bin)
// against brute force: the mean and mean square of luminance(sample().weight)
// over many samples, T included.
TEST(YarnIntegrals, WeightMomentsMatchSampling) {
    for (const char* name : kModels) {
        const YarnBsdf& bsdf = testBsdf(name);
        for (const Vec3& wi : {yarnDirection(20, 30), yarnDirection(75, -100)}) {
            const DirectionalIntegrals d = integrateDirections(bsdf, wi);
            EXPECT_NEAR(d.weightMean, d.albedoLuminance, 1e-9);  // the pdf covers R + M
            EXPECT_GE(d.weightSecondMoment, d.weightMean * d.weightMean);
            EXPECT_GE(d.weightMax, d.weightMean);
            const int64_t n = testing::scaled(100000);
            Rng rng(21, 22);
            double sum = 0, sumSq = 0, sumFourth = 0;
            for (int64_t k = 0; k < n; ++k) {
                const BsdfSample s =
                    bsdf.sample(wi, {rng.uniform(), rng.uniform(), rng.uniform()}, rng);
                const double w = luminance(s.weight);
                sum += w, sumSq += w * w, sumFourth += w * w * w * w;
            }
            const double mean = sum / n, meanSq = sumSq / n;
            const double sigma = std::sqrt(std::max(0.0, meanSq - mean * mean) / n);
            const double sigmaSq = std::sqrt(std::max(0.0, sumFourth / n - meanSq * meanSq) / n);
            EXPECT_NEAR(mean, d.weightMean, 4.5 * sigma + 1e-3) << name << " " << wi;
            EXPECT_NEAR(meanSq, d.weightSecondMoment, 5 * sigmaSq + 2e-3 * meanSq)
                << name << " " << wi;
        }
    }
}

TEST(YarnIntegrals, MeanSampleWeightIsTheQuadratureAlbedo) {
    for (const char* name : kModels) {
        const YarnBsdf& bsdf = testBsdf(name);
        for (const Vec3& wi :
             {yarnDirection(10, 0), yarnDirection(60, 90), yarnDirection(80, -30)}) {
            const Rgb albedo = integrateDirections(bsdf, wi).albedo();
            Rng rng(13, 14);
            const testing::WeightMean w =
                testing::meanSampleWeight(bsdf, wi, testing::scaled(100000), rng);
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(w.mean[c], albedo[c], 4.5 * w.standardError[c] + 1e-3)
                    << name << " " << wi << " channel " << c;
            }
        }
    }
}

// The energy guard: at the nodes of its M table the guarded albedo is at most
// 1 (up to the difference between its quadrature and the finer one here, and
// the interpolation of its R table), and it leaves S_M alone wherever the
// model's own albedo stays clearly below 1.
TEST(YarnIntegrals, EnergyGuardScalesOnlyOvershootingDirections) {
    for (const char* name : kModels) {
        const YarnBsdf& guarded = testBsdf(name);
        const YarnBsdf raw(testModel(name), name, YarnBsdfOptions{false});
        EXPECT_FALSE(raw.model().energyGuard().active());
        int scaled = 0, nodes = 0;
        double worstRaw = 0;
        // Nodes of the M table (the R table's part is interpolated there);
        // fewer of them under the sanitizers.
        const int stride = testing::sampleScale() < 1 ? 3 : 1;
        for (int a = 0; a < EnergyGuard::kTheta; a += 2 * stride)
            for (int b = 0; b < EnergyGuard::kPhi; b += 4 * stride) {
                const Vec3 wi = sphericalDirection(EnergyGuard::polarAngle(a),
                                                   -kPi + kTwoPi * b / EnergyGuard::kPhi);
                const Rgb before = integrateDirections(raw, wi).albedo();
                const Rgb after = integrateDirections(guarded, wi).albedo();
                const Rgb scale = guarded.model().multipleScatteringScale(wi);
                ++nodes;
                worstRaw = std::max(worstRaw, before.maxComponent());
                for (int c = 0; c < 3; ++c) {
                    EXPECT_LE(after[c], 1 + 5e-3) << name << " " << wi << " channel " << c;
                    if (before[c] < 0.995) {
                        EXPECT_EQ(scale[c], 1.0) << name << " " << wi;
                    }
                    if (scale[c] < 1) {
                        ++scaled;
                        EXPECT_NEAR(after[c], 1.0, 1e-2) << name << " " << wi << " channel " << c;
                    }
                }
            }
        std::printf(
            "%s: energy guard active on %d of %d (node, channel) pairs tested; largest "
            "raw albedo %.3f\n",
            name, scaled, 3 * nodes, worstRaw);
    }
}

// docs/design.md 7 / issue 6: the directional albedo of the BSDF the renderer uses
// never exceeds 1 + 1e-2, between the guard's nodes included.
TEST(YarnIntegrals, AlbedoNeverExceedsOne) {
    const int count = testing::sampleScale() < 1 ? 12 : 60;
    for (const char* name : kModels) {
        const YarnBsdf& bsdf = testBsdf(name);
        std::vector<Vec3> incident;
        for (double theta : {0.0, 30.0, 60.0, 80.0, 89.0, 89.99})
            for (double phi : {0.0, 45.0, 90.0, 150.0})
                incident.push_back(yarnDirection(theta, phi));
        Rng rng(15, 16);
        for (int k = 0; k < count; ++k) incident.push_back(randomUnitVector(rng));
        double worst = 0;
        Vec3 worstWi;
        for (const Vec3& wi : incident) {
            const DirectionalIntegrals d = integrateDirections(bsdf, wi);
            const double top = d.albedo().maxComponent();
            if (top > worst) worst = top, worstWi = wi;
            EXPECT_LE(top, 1 + 1e-2) << name << " wi " << wi << " albedo " << d.albedo();
        }
        std::printf("%s: largest directional albedo %.4f at wi %s over %zu directions\n", name,
                    worst, text(worstWi).c_str(), incident.size());
    }
}

// The shipped models (models/<preset>.json, README "Shipped models"): each is
// the named preset's fiber and ply, loads into the renderer's BSDF, and keeps
// its directional albedo within 1 + 3e-2. That is a wider margin than the test
// models' 1e-2: cotton's 16M-path M map is sharper near grazing incidence than
// the energy guard's tables resolve between their nodes (measured 1.027 at
// theta 80, the others <= 1.005; without the guard cotton reaches 1.10).
TEST(YarnBsdf, ShippedModelsArePresetsAndConserveEnergy) {
    for (const MaterialPreset& preset : materialPresets()) {
        const std::string name(preset.name);
        SCOPED_TRACE(name);
        const std::string path = std::string(WEFT_SOURCE_DIR) + "/models/" + name + ".json";
        const YarnModel model = loadYarnModel(path);
        EXPECT_EQ(model.fiber.toJson(), preset.fiber.toJson());
        EXPECT_EQ(model.ply.fibers, preset.ply.fibers);
        EXPECT_EQ(model.ply.density, preset.ply.density);
        EXPECT_EQ(model.ply.twist, preset.ply.twist);
        EXPECT_EQ(model.fit.at("gather").at("paths"), 16000000);
        EXPECT_GE(model.fit.at("commands").size(), 3u);

        // The energy check of one material under the (slow) sanitizers.
        if (testing::sampleScale() < 1 && name != "fleece") continue;
        const YarnBsdf bsdf(model, path);
        double worst = 0;
        for (double theta : {0.0, 30.0, 60.0, 80.0, 89.0})
            for (double phi : {0.0, 45.0, 90.0, 150.0}) {
                const double top =
                    integrateDirections(bsdf, yarnDirection(theta, phi)).albedo().maxComponent();
                worst = std::max(worst, top);
                EXPECT_LE(top, 1 + 3e-2) << "theta " << theta << " phi " << phi;
            }
        std::printf("%s: largest directional albedo %.4f over 20 directions\n", name.c_str(),
                    worst);
    }
}

// ------------------------------------------------------------------ loading --

TEST(YarnBsdf, RejectsModelsTheRendererCannotUse) {
    const YarnModel good = testModel("fleece-small");
    YarnModel m = good;
    m.tNet = NetworkWeights::initialised({3, 7, 1}, OutputFunction::Exp, 1);
    testing::expectInputError([&] { YarnBsdf(m, "a.json"); },
                              {"a.json: t_net.output", "\"sigmoid\"", "got \"exp\""});
    m = good;
    m.mNet = NetworkWeights::initialised({6, 21, 3}, OutputFunction::Sigmoid, 1);
    testing::expectInputError([&] { YarnBsdf(m, "a.json"); }, {"a.json: m_net.output", "\"exp\""});
    m = good;
    m.tNet = NetworkWeights::initialised({4, 7, 1}, OutputFunction::Sigmoid, 1);
    testing::expectInputError([&] { YarnBsdf(m, "a.json"); },
                              {"a.json: t_net", "3 inputs and 1 output", "got 4-7-1"});
    m = good;
    m.mNet = NetworkWeights::initialised({6, 100, 3}, OutputFunction::Exp, 1);
    testing::expectInputError([&] { YarnBsdf(m, "a.json"); }, {"a.json: m_net", "widths up to 64"});
    m = good;
    m.sampling.kappaM = 1.5;
    testing::expectInputError([&] { YarnBsdf(m, "a.json"); }, {"a.json: ", "kappa_m", "[0, 1]"});
    m = good;
    m.fiber.betaRDeg = 0;
    testing::expectInputError([&] { YarnBsdf(m, "a.json"); }, {"a.json: ", "beta_r_deg"});
    m = good;
    m.rLobe.tiltDeg = 95;
    testing::expectInputError([&] { YarnBsdf(m, "a.json"); }, {"a.json: ", "tilt_deg"});
}

class YarnBsdfFile : public testing::TempDirTest {};

TEST_F(YarnBsdfFile, LoadNamesTheFile) {
    const std::string original = readFile(modelPath("fleece-small"));
    auto expectLoadError = [&](const std::string& from, const std::string& to,
                               std::initializer_list<std::string> parts) {
        std::string bad = original;
        const size_t at = bad.find(from);
        ASSERT_NE(at, std::string::npos) << from;
        bad.replace(at, from.size(), to);
        writeFileAtomic(path("bad.json"), bad);
        testing::expectInputError([&] { YarnBsdf::load(path("bad.json")); }, parts);
    };
    expectLoadError("\"version\": 1", "\"version\": 4", {"bad.json", "version"});
    expectLoadError("\"kappa_m\"", "\"kappa_mm\"", {"bad.json", "sampling", "kappa_mm"});
    expectLoadError("\"output\": \"sigmoid\"", "\"output\": \"exp\"", {"bad.json", "t_net.output"});
    expectLoadError("\"bias\": [", "\"bias\": [NaN, ", {"bad.json"});
    EXPECT_NO_THROW(YarnBsdf::load(modelPath("fleece-small"), YarnBsdfOptions{false}));
}

}  // namespace
}  // namespace weft

namespace weft {
namespace {

// The batches of core/bsdf.h (issue 45): prepareBatch, evalPdfBatch and
// sampleBatch must give every query the single call's bits (the batched
// path tracer's images equal the per-path one's), for incidents on both
// sides, any mix of lobes, every sampling strategy, with the guard and
// without, in batches that are partial, single and larger than a chunk.
TEST(YarnBsdf, BatchesGiveTheSingleCallsBits) {
    for (const char* name : sanitizerSubset(kModels)) {
        for (const YarnSampling sampling :
             {YarnSampling::Tabulated, YarnSampling::Fitted, YarnSampling::Cosine}) {
            for (const bool guard : {true, false}) {
                // Under the sanitizers the renderer's default alone (tables take long there).
                if (testing::sampleScale() < 1 && (sampling != YarnSampling::Tabulated || !guard))
                    continue;
                const YarnBsdf bsdf(testModel(name), name, YarnBsdfOptions{guard, sampling});
                Rng rng(11, 3);
                for (const size_t count : {size_t(1), size_t(15), size_t(70), size_t(200)}) {
                    testing::BatchQueries q(bsdf, count, rng, 5);
                    std::vector<BsdfEval> evals(count);
                    bsdf.evalPdfBatch(q.batchConst.data(), q.wo.data(), count, evals.data());
                    std::vector<BsdfSample> samples(count);
                    bsdf.sampleBatch(q.batchConst.data(), q.u.data(), q.rngPtr.data(), count,
                                     samples.data());
                    for (size_t k = 0; k < count; ++k) {
                        SCOPED_TRACE(std::string(name) + " sampling " +
                                     std::to_string(static_cast<int>(sampling)) + " guard " +
                                     std::to_string(guard) + " query " + std::to_string(k) +
                                     " of " + std::to_string(count));
                        const BsdfEval want = bsdf.evalPdf(q.single[k], q.wo[k]);
                        ASSERT_EQ(evals[k].value, want.value);
                        ASSERT_EQ(evals[k].pdf, want.pdf);
                        // The prepared incidents agree too: the same values at another wo.
                        ASSERT_EQ(bsdf.evalPdf(q.batch[k], -q.wo[k]).value,
                                  bsdf.evalPdf(q.single[k], -q.wo[k]).value);
                        const BsdfSample s = bsdf.sample(q.single[k], q.u[k], q.rngSingle[k]);
                        ASSERT_EQ(samples[k].lobe, s.lobe);
                        ASSERT_EQ(samples[k].wo, s.wo);
                        ASSERT_EQ(samples[k].weight, s.weight);
                        ASSERT_EQ(samples[k].pdf, s.pdf);
                        ASSERT_EQ(samples[k].isDelta, s.isDelta);
                        ASSERT_EQ(q.rngBatch[k].nextU32(), q.rngSingle[k].nextU32());
                    }
                }
            }
        }
    }
}

}  // namespace
}  // namespace weft
