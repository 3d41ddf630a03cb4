// The dual-scattering baseline (dual_scattering.h) against independent truth:
// its pdf integrates to 1, its samples follow its pdf (chi-square), a ply of
// lossless fibers passes the white furnace bound, the mean sample weight is
// the albedo by quadrature, the fiber count n_f of analytic cases, and the
// front-lit limit where the model is the fiber's own BCSDF.
#include "weft/yarn/dual_scattering.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include "weft/core/chi2.h"
#include "weft/core/error.h"
#include "weft/core/math.h"
#include "weft/core/quadrature.h"
#include "weft/core/rng.h"
#include "weft/core/sampling.h"
#include "weft/core/test_util.h"
#include "weft/yarn/material_preset.h"
#include "weft/yarn/sphere_rule.h"

namespace weft {
namespace {

const MaterialPreset& preset(const char* name) { return findMaterialPreset(name); }

Vec3 yarnDirection(double thetaDeg, double phiDeg) {
    return sphericalDirection(radians(thetaDeg), radians(phiDeg));
}

// Incident directions (polar angle from n, azimuth from t) on both sides of
// the surface, a grazing one included.
std::vector<Vec3> incidentDirections() {
    return {yarnDirection(0, 0),   yarnDirection(35, 50),   yarnDirection(60, 140),
            yarnDirection(85, 20), yarnDirection(120, -60), yarnDirection(150, 100)};
}

// A rule over the sphere that resolves the fiber's R lobe for wi (mirrored
// for the lower side, where the BSDF mirrors both directions).
double integrate(const DualScatteringBsdf& bsdf, const Vec3& wi,
                 const std::function<double(const Vec3&)>& f) {
    const bool flip = wi.z < 0;
    const SphereRule rule = surfaceFiberSphereRule(
        bsdf.frame(), radians(bsdf.fiber().params().betaRDeg), flip ? mirrored(wi) : wi, 2);
    double sum = 0;
    for (size_t k = 0; k < rule.directions.size(); ++k) {
        const Vec3& d = rule.directions[k];
        sum += f(flip ? mirrored(d) : d) * rule.weights[k];
    }
    return sum;
}

TEST(DualScattering, PdfIntegratesToOne) {
    for (const char* name : {"fleece", "silk", "gabardine"}) {
        const MaterialPreset& p = preset(name);
        const DualScatteringBsdf bsdf(p.fiber, p.ply);
        for (const Vec3& wi : incidentDirections()) {
            const double total =
                integrate(bsdf, wi, [&](const Vec3& wo) { return bsdf.pdf(wi, wo); });
            EXPECT_NEAR(total, 1.0, 2e-3) << name << " wi " << wi;
        }
    }
}

TEST(DualScattering, SamplesFollowThePdf) {
    const std::vector<Vec3> incident = {yarnDirection(35, 50), yarnDirection(60, 140),
                                        yarnDirection(110, -120)};
    const double alpha = sidakCorrectedLevel(0.01, static_cast<int>(2 * incident.size()));
    const SphereGrid grid{90, 48};
    for (const char* name : {"fleece", "cotton"}) {
        const MaterialPreset& p = preset(name);
        const DualScatteringBsdf bsdf(p.fiber, p.ply);
        for (const Vec3& wi : incident) {
            const int64_t n = testing::scaled(100000);
            std::vector<double> observed(grid.cells(), 0);
            Rng rng(5, static_cast<uint64_t>(1e6 * (wi.x + 2 * wi.y + 3 * wi.z) + 1e7));
            for (int64_t k = 0; k < n; ++k) {
                const BsdfSample s =
                    bsdf.sample(wi, {rng.uniform(), rng.uniform(), rng.uniform()}, rng);
                ASSERT_TRUE(s.valid()) << name << " wi " << wi;
                ASSERT_FALSE(s.isDelta);
                observed[grid.cellOf(bsdf.frame().toLocal(s.wo))] += 1;
            }
            const std::vector<double> expected = grid.expectedCounts(
                [&](const Vec3& local) { return bsdf.pdf(wi, bsdf.frame().fromLocal(local)); },
                static_cast<double>(n));
            const Chi2Result r = chi2Test(observed, expected);
            std::printf("%s, wi %g %g %g: chi2 %.1f, dof %d, p %.3g\n", name, wi.x, wi.y, wi.z,
                        r.statistic, r.dof, r.pValue);
            EXPECT_GT(r.pValue, alpha) << name << " wi " << wi;
        }
    }
}

// A finer rule than the BSDF's own for its energy clamp: theta panels of 3.75
// degrees, and of beta_R / 2 within 6 beta_R of the specular cone; phi panels
// of 11.25 degrees, and of 0.5 degrees within 10 degrees of the surface plane,
// where the light starts to cross fibers.
Rgb integrateFinely(const DualScatteringBsdf& bsdf, const Vec3& wi,
                    const std::function<Rgb(const Vec3&)>& f) {
    const bool flip = wi.z < 0;
    const Vec3 upper = flip ? mirrored(wi) : wi;
    const double thetaI = bsdf.frame().longitudinalAngle(upper);
    const double betaR = radians(bsdf.fiber().params().betaRDeg);
    std::vector<double> thetaEdges, phiEdges;
    quadrature::uniformEdges(-kHalfPi, kHalfPi, 48, &thetaEdges);
    quadrature::uniformEdges(std::max(-kHalfPi, -thetaI - 6 * betaR),
                             std::min(kHalfPi, -thetaI + 6 * betaR), 24, &thetaEdges);
    std::sort(thetaEdges.begin(), thetaEdges.end());
    quadrature::uniformEdges(-kPi, kPi, 32, &phiEdges);
    quadrature::uniformEdges(kHalfPi - radians(10), kHalfPi + radians(10), 40, &phiEdges);
    quadrature::uniformEdges(-kHalfPi - radians(10), -kHalfPi + radians(10), 40, &phiEdges);
    std::sort(phiEdges.begin(), phiEdges.end());
    const SphereRule rule = surfaceFiberRule(bsdf.frame(), thetaEdges, phiEdges);
    Rgb sum;
    for (size_t k = 0; k < rule.directions.size(); ++k) {
        const Vec3& d = rule.directions[k];
        sum += f(flip ? mirrored(d) : d) * rule.weights[k];
    }
    return sum;
}

TEST(DualScattering, LosslessFibersPassTheWhiteFurnace) {
    // C_TT = 1: each fiber scatters all it receives (albedo F + (1 - F) = 1).
    // Zinke's terms alone exceed 1 for such a ply; the energy clamp brings
    // the albedo to at most 1 (up to its bilinear interpolation between
    // nodes), and the model still returns most of the energy.
    FiberParams fiber = preset("fleece").fiber;
    fiber.cTT = Rgb(1.0);
    const PlyParams ply = preset("fleece").ply;
    const DualScatteringBsdf clamped(fiber, ply);
    DualScatteringOptions raw;
    raw.energyClamp = false;
    const DualScatteringBsdf unclamped(fiber, ply, raw);
    double largestRaw = 0, largest = 0;
    // Near grazing (polar 80-100 degrees) is where Zinke's terms exceed 1 most.
    for (const double polar : {10, 55, 80, 89, 100, 150}) {
        for (const double azimuth : {0, 60, 120}) {
            const Vec3 wi = yarnDirection(polar, azimuth);
            const double albedo = integrateFinely(clamped, wi, [&](const Vec3& wo) {
                                      return clamped.eval(wi, wo);
                                  }).maxComponent();
            const double albedoRaw = integrateFinely(unclamped, wi, [&](const Vec3& wo) {
                                         return unclamped.eval(wi, wo);
                                     }).maxComponent();
            EXPECT_LE(albedo, 1.02) << "wi " << wi;
            EXPECT_GT(albedo, 0.3) << "wi " << wi;
            largestRaw = std::max(largestRaw, albedoRaw);
            largest = std::max(largest, albedo);
        }
    }
    std::printf("largest albedo %.4f (without the clamp %.4f)\n", largest, largestRaw);
    EXPECT_GT(largestRaw, 1.0) << "the clamp should have had work to do";
}

TEST(DualScattering, MeanSampleWeightIsTheAlbedo) {
    // E[eval / pdf] over the sampler = the integral of eval: sample(), eval()
    // and pdf() against a quadrature of eval alone.
    const MaterialPreset& p = preset("polyester");
    const DualScatteringBsdf bsdf(p.fiber, p.ply);
    for (const Vec3& wi : {yarnDirection(30, 70), yarnDirection(130, 20)}) {
        Rng rng(9, 1);
        const testing::WeightMean w =
            testing::meanSampleWeight(bsdf, wi, testing::scaled(200000), rng);
        for (int c = 0; c < 3; ++c) {
            const double quadrature =
                integrate(bsdf, wi, [&](const Vec3& wo) { return bsdf.eval(wi, wo)[c]; });
            EXPECT_NEAR(w.mean[c], quadrature, 5 * w.standardError[c] + 1e-3 * quadrature)
                << "wi " << wi << " channel " << c;
        }
    }
}

TEST(DualScattering, FibersCrossedByTheLight) {
    const MaterialPreset& p = preset("cotton");
    const DualScatteringBsdf bsdf(p.fiber, p.ply);
    const double centreChord = 4 / kPi * std::sqrt(p.ply.fibers * p.ply.density);
    // Straight into the ply: the chord through the centre.
    EXPECT_NEAR(bsdf.fibersCrossed({0, 0, -1}), centreChord, 1e-12);
    // At 60 degrees from -n in the cross-section: the chord is cos(60) as long;
    // the component along the axis does not change the chord's cross-section.
    EXPECT_NEAR(bsdf.fibersCrossed(normalize(Vec3{0.7, std::sin(radians(60)), -0.5})),
                0.5 * centreChord, 1e-12);
    // Light from outside, or along the axis, crosses nothing.
    EXPECT_EQ(bsdf.fibersCrossed(yarnDirection(20, 40)), 0.0);
    EXPECT_EQ(bsdf.fibersCrossed({1, 0, 0}), 0.0);
}

TEST(DualScattering, FrontLitWithoutBackScatteringIsTheFiberBcsdf) {
    // Light from outside the ply (wo.z > 0: n_f = 0, D = 1) and d_b = 0: the
    // model is the fiber's own BCSDF in the surface fiber frame.
    const MaterialPreset& p = preset("silk");
    DualScatteringOptions options;
    options.backScale = 0;
    options.energyClamp = false;
    const DualScatteringBsdf bsdf(p.fiber, p.ply, options);
    const FiberBcsdf fiber(p.fiber);
    for (const Vec3& wi : incidentDirections()) {
        for (const Vec3& wo :
             {yarnDirection(10, 30), yarnDirection(40, 100), yarnDirection(70, 160)}) {
            const Vec3 o = wi.z < 0 ? mirrored(wo) : wo;  // on wi's side
            const Rgb expected = fiber.eval(bsdf.frame().toLocal(wi.z < 0 ? mirrored(wi) : wi),
                                            bsdf.frame().toLocal(wo));
            const Rgb value = bsdf.eval(wi, o);
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(value[c], expected[c], 1e-12 * (1 + expected[c])) << wi << " " << wo;
        }
    }
}

// The energy clamp computes half its nodes and mirrors the rest, relying on
// the ply's symmetry under a half turn about n: check it on the model itself.
TEST(DualScattering, HalfTurnAboutTheNormalIsASymmetry) {
    const auto halfTurn = [](const Vec3& v) { return Vec3{-v.x, -v.y, v.z}; };
    Rng rng(7, 1);
    for (const char* name : {"fleece", "silk", "cotton"}) {
        const MaterialPreset& p = preset(name);
        DualScatteringOptions raw;
        raw.energyClamp = false;
        const DualScatteringBsdf bsdf(p.fiber, p.ply, raw);
        for (int k = 0; k < 2000; ++k) {
            const Vec3 wi = sampleUniformSphere(rng.uniform(), rng.uniform());
            const Vec3 wo = sampleUniformSphere(rng.uniform(), rng.uniform());
            const Rgb a = bsdf.eval(wi, wo), b = bsdf.eval(halfTurn(wi), halfTurn(wo));
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(a[c], b[c], 1e-9 * std::max(1.0, a[c])) << name << " pair " << k;
        }
        const DualScatteringBsdf clamped(p.fiber, p.ply);
        for (const Vec3& wi : incidentDirections()) {
            const Rgb a = clamped.clampScale(wi), b = clamped.clampScale(halfTurn(wi));
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 1e-12) << name;
        }
    }
}

TEST(DualScattering, ParametersAreValidated) {
    const MaterialPreset& p = preset("fleece");
    DualScatteringOptions bad;
    bad.forwardScale = 1.5;
    EXPECT_THROW(DualScatteringBsdf(p.fiber, p.ply, bad), InputError);
    bad.forwardScale = std::nan("");
    EXPECT_THROW(DualScatteringBsdf(p.fiber, p.ply, bad), InputError);
    PlyParams ply = p.ply;
    ply.density = 0;
    EXPECT_THROW(DualScatteringBsdf(p.fiber, ply), InputError);
}

}  // namespace
}  // namespace weft
