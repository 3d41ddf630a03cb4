#include "weft/yarn/yarn_lobes.h"

#include <gtest/gtest.h>

#include <cmath>

#include "weft/core/math.h"
#include "weft/core/test_util.h"
#include "weft/yarn/material_preset.h"

namespace weft {
namespace {

const FiberParams& fleeceFiber() { return findMaterialPreset("fleece").fiber; }

// Integral over the sphere of f(w) by Simpson's rule in (cos theta, phi) of the yarn frame.
template <typename F>
double sphereIntegral(const F& f, int n = 400) {
    return testing::simpson(
        [&](double z) {
            const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
            return testing::simpson(
                [&](double phi) { return f(Vec3{s * std::cos(phi), s * std::sin(phi), z}); }, -kPi,
                kPi, n);
        },
        -1.0, 1.0, n);
}

const Vec3 kIncident[] = {sphericalDirection(0.05, 0.3), sphericalDirection(radians(45), 0.0),
                          sphericalDirection(radians(60), radians(100)),
                          sphericalDirection(radians(85), radians(-30))};

TEST(SurfaceFiberFrame, TiltTurnsTangentTowardsB) {
    const double tilt = SurfaceFiberFrame::tiltDegOfTwist(0.24);
    EXPECT_NEAR(tilt, degrees(std::atan(kPi * 0.24)), 1e-12);
    const SurfaceFiberFrame frame = SurfaceFiberFrame::fromTiltDeg(tilt);
    // The surface fiber tangent t~ = cos t + sin b has local coordinates (1, 0, 0).
    const Vec3 tTilde{std::cos(radians(tilt)), std::sin(radians(tilt)), 0};
    const Vec3 local = frame.toLocal(tTilde);
    EXPECT_NEAR(local.x, 1, 1e-12);
    EXPECT_NEAR(local.y, 0, 1e-12);
    const Vec3 back = frame.fromLocal(frame.toLocal({0.3, -0.4, 0.5}));
    EXPECT_NEAR(back.x, 0.3, 1e-12);
    EXPECT_NEAR(back.y, -0.4, 1e-12);
    EXPECT_NEAR(back.z, 0.5, 1e-12);
}

TEST(TruncatedGaussian, NormalisedAndSamplerInvertsItsCdf) {
    for (double beta : {radians(3.0), radians(20.0), radians(80.0)}) {
        const TruncatedGaussian g(beta);
        for (double mu : {0.0, 0.7, -1.2, kPi / 2}) {
            EXPECT_NEAR(testing::simpson([&](double t) { return g.pdf(t, mu); }, -kPi / 2, kPi / 2, 20000),
                        1.0, 1e-6)
                << beta << " " << mu;
            // CDF(sample(u)) = u, CDF by independent quadrature of the pdf.
            for (double u : {0.05, 0.3, 0.5, 0.9}) {
                const double theta = g.sample(mu, u);
                const double cdf =
                    testing::simpson([&](double t) { return g.pdf(t, mu); }, -kPi / 2, theta, 20000);
                EXPECT_NEAR(cdf, u, 1e-5) << beta << " " << mu << " " << u;
            }
        }
    }
}

// Paper eq. 10: both continuous sampling densities integrate to 1 over the sphere.
TEST(SamplingLobes, DensitiesIntegrateToOne) {
    for (const SamplingParams& p :
         {SamplingParams{0.3, 20, 40, 0.5}, SamplingParams{0.5, 8, 15, 0.95}, SamplingParams{0.1, 60, 150, 0.2}}) {
        const SamplingLobes lobes(fleeceFiber(), 37, p);
        for (const Vec3& wi : kIncident) {
            EXPECT_NEAR(sphereIntegral([&](const Vec3& wo) { return lobes.pdfM(wi, wo); }, 600), 1.0, 2e-3)
                << wi;
            EXPECT_NEAR(sphereIntegral([&](const Vec3& wo) { return lobes.pdfR(wi, wo); }, 600), 1.0, 2e-3)
                << wi;
        }
    }
}

TEST(SamplingLobes, RejectsOutOfRangeParameters) {
    testing::expectInputError([] { SamplingLobes(fleeceFiber(), 0, {1.5, 20, 40, 0.5}); },
                              {"kappa_r", "[0, 1]"});
    testing::expectInputError([] { SamplingLobes(fleeceFiber(), 0, {0.5, 0, 40, 0.5}); },
                              {"beta_m_deg", "(0, 90]"});
    testing::expectInputError([] { SamplingLobes(fleeceFiber(), 0, {0.5, 20, NAN, 0.5}); },
                              {"gamma_m_deg"});
}

// Eq. 8 with no tilt is the fiber model in the yarn frame (fiber tangent t),
// scaled by 1 - P(T); zero when either direction is below the surface.
TEST(RLobe, IsEq8InTheSurfaceFiberFrame) {
    const FiberBcsdf fiber(fleeceFiber());
    const RLobe flat(fleeceFiber(), RLobeParams{0.0, {}});
    const Vec3 wi = normalize(Vec3{0.3, 0.2, 0.9}), wo = normalize(Vec3{-0.5, 0.4, 0.6});
    const Rgb expected = fiber.eval(wi, wo) * 0.75;
    const Rgb got = flat.eval(wi, wo, 0.25);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], expected[c], 1e-12);
    EXPECT_TRUE(flat.eval(wi, {wo.x, wo.y, -wo.z}, 0.25).isBlack());
    EXPECT_TRUE(flat.eval({wi.x, wi.y, -wi.z}, wo, 0.25).isBlack());

    // With tilt: the same as the fiber model on directions rotated by -tilt about n.
    const double tilt = 30;
    const RLobe tilted(fleeceFiber(), RLobeParams{tilt, {}});
    const double c = std::cos(radians(tilt)), s = std::sin(radians(tilt));
    auto rotate = [&](const Vec3& w) { return Vec3{c * w.x + s * w.y, -s * w.x + c * w.y, w.z}; };
    const Rgb expectedTilted = fiber.eval(rotate(wi), rotate(wo));
    const Rgb gotTilted = tilted.eval(wi, wo, 0.0);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(gotTilted[k], expectedTilted[k], 1e-12);
}

// The masking term is symmetric in wi and wo and clamped to [0, 1]; the lobe
// never reflects more than the fiber's albedo times 1 - P(T).
TEST(RLobe, MaskingIsReciprocalBoundedAndEnergyConserving) {
    const RLobe masked(fleeceFiber(), RLobeParams{37, {0.9, -0.5, 0.8, 0.3}});
    const Vec3 a = normalize(Vec3{0.3, 0.2, 0.9}), b = normalize(Vec3{-0.5, 0.4, 0.2});
    EXPECT_DOUBLE_EQ(masked.masking(a, b), masked.masking(b, a));
    for (double z1 : {0.01, 0.5, 1.0})
        for (double z2 : {0.01, 0.5, 1.0}) {
            const double m = masked.masking({0, std::sqrt(1 - z1 * z1), z1}, {0, std::sqrt(1 - z2 * z2), z2});
            EXPECT_GE(m, 0.0);
            EXPECT_LE(m, 1.0);
        }
    const FiberBcsdf fiber(fleeceFiber());
    for (const Vec3& wi : kIncident) {
        const double energy = sphereIntegral([&](const Vec3& wo) { return masked.eval(wi, wo, 0.2).average(); });
        const Vec3 local = masked.frame().toLocal(wi);
        EXPECT_LE(energy, 0.8 * fiber.albedo(local).average() + 1e-3) << wi;
        EXPECT_GT(energy, 0.0);
    }
}

}  // namespace
}  // namespace weft
