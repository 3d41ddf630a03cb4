// Tests of the objects' materials against independent truth: the white
// furnace (a white Lambertian surface reflects all it receives), the pdf
// integrating to 1 (to the share of microfacet samples above the surface),
// reciprocity, sample weights against eval / pdf, and chi-square of the
// samplers against their pdfs.
#include "weft/render/surface_bsdf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "weft/core/chi2.h"
#include "weft/core/math.h"
#include "weft/core/test_util.h"

namespace weft::render {
namespace {

// The integrals over the sphere of f cos (eval) and of the pdf at wi, by the
// midpoint rule in (cos theta, phi).
struct SphereIntegrals {
    Rgb energy;
    double pdf = 0;
};
SphereIntegrals integrate(const Bsdf& bsdf, const Vec3& wi, int n = 800) {
    const BsdfSlice slice = bsdf.slice(wi);
    SphereIntegrals s;
    const double dz = 2.0 / n, dphi = kTwoPi / n;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
            const double z = -1 + (a + 0.5) * dz, r = safeSqrt(1 - z * z);
            const double phi = (b + 0.5) * dphi;
            const BsdfEval e = slice.evalPdf({r * std::cos(phi), r * std::sin(phi), z});
            s.energy += e.value * (dz * dphi);
            s.pdf += e.pdf * dz * dphi;
        }
    return s;
}

const std::vector<Vec3> kIncident = {normalize(Vec3{0.3, -0.2, 0.9}),
                                     normalize(Vec3{-0.8, 0.1, 0.3}),
                                     normalize(Vec3{0.2, 0.5, -0.6})};

TEST(DiffuseBsdf, WhiteFurnaceAndPdfIntegrateToOneOnEitherSide) {
    const DiffuseBsdf white(Rgb(1.0), "floor");
    const DiffuseBsdf grey({0.2, 0.5, 0.8}, "floor");
    for (const Vec3& wi : kIncident) {
        const SphereIntegrals s = integrate(white, wi);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.energy[c], 1.0, 2e-5) << wi;
        EXPECT_NEAR(s.pdf, 1.0, 2e-5) << wi;
        const SphereIntegrals g = integrate(grey, wi);
        EXPECT_NEAR(g.energy.b, 0.8, 2e-5);
        // Nothing is transmitted: wo on the other side is black.
        EXPECT_TRUE(white.eval(wi, {0, 0, wi.z > 0 ? -1.0 : 1.0}).isBlack());
    }
}

TEST(ConductorBsdf, ReciprocalConservingAndItsPdfIntegratesToTheSamplesAboveTheSurface) {
    for (const double roughness : {0.1, 0.4, 1.0}) {
        const ConductorBsdf metal(Rgb(1.0), roughness, "mesh");
        for (const Vec3& wi : kIncident) {
            const SphereIntegrals s = integrate(metal, wi, 1600);
            // A white metal loses what masking and shadowing take (single
            // scattering: about 0.78 at roughness 0.4, 0.3-0.45 at 1), never gains.
            EXPECT_LE(s.energy.r, 1.0 + 1e-3) << roughness << " " << wi;
            EXPECT_GT(s.energy.r, 0.25) << roughness << " " << wi;
            // The pdf integrates to the share of sampled wo above the surface.
            int above = 0;
            const int samples = 200000;
            Rng rng(7, 3);
            for (int k = 0; k < samples; ++k)
                above += metal.sample(wi, {rng.uniform(), rng.uniform(), rng.uniform()}).valid();
            EXPECT_NEAR(s.pdf, static_cast<double>(above) / samples,
                        4e-3 + (roughness < 0.2 ? 2e-2 : 0.0))
                << roughness << " " << wi;
            // Reciprocity: f(wi, wo) = f(wo, wi).
            for (const Vec3& wo : kIncident) {
                const double fo = metal.eval(wi, wo).r / std::abs(wo.z);
                const double fi = metal.eval(wo, wi).r / std::abs(wi.z);
                EXPECT_NEAR(fo, fi, 1e-9 * (fo + fi)) << wi << wo;
            }
        }
    }
}

// The microfacet identities (Heitz 2014): D is a distribution of projected
// area, integral of D(h) cos h = 1, and the masking conserves it for every
// direction: integral of G1(w) D(h) max(0, w.h) = cos theta_w.
TEST(ConductorBsdf, MicrofacetDistributionAndMaskingHoldTheirIdentities) {
    for (const double roughness : {0.05, 0.3, 1.0}) {
        const ConductorBsdf metal(Rgb(1.0), roughness, "mesh");
        const int n = 2000;
        const double dz = 1.0 / n, dphi = kTwoPi / n;
        for (const Vec3& w :
             {Vec3{0, 0, 1}, normalize(Vec3{0.6, 0.2, 0.5}), normalize(Vec3{0.9, 0, 0.15})}) {
            double area = 0, projected = 0;
            for (int a = 0; a < n; ++a)
                for (int b = 0; b < n; ++b) {
                    // z from 1 down, finely near the pole where D peaks: z = 1 - u^2.
                    const double u = (a + 0.5) * dz, z = 1 - u * u, jacobian = 2 * u;
                    const double r = safeSqrt(1 - z * z), phi = (b + 0.5) * dphi;
                    const Vec3 h{r * std::cos(phi), r * std::sin(phi), z};
                    const double d = metal.distribution(h) * jacobian * dz * dphi;
                    area += d * z;
                    projected += d * std::max(0.0, dot(w, h));
                }
            EXPECT_NEAR(area, 1.0, 2e-3) << roughness;
            EXPECT_NEAR(metal.masking(w) * projected, w.z, 2e-3) << roughness << " " << w;
        }
    }
}

TEST(SurfaceBsdfs, SamplesMatchTheirPdfAndWeights) {
    const DiffuseBsdf diffuse({0.3, 0.6, 0.9}, "floor");
    const ConductorBsdf metal({0.9, 0.6, 0.3}, 0.3, "mesh");
    const double level = sidakCorrectedLevel(0.01, 2 * static_cast<int>(kIncident.size()));
    for (const Bsdf* bsdf : {static_cast<const Bsdf*>(&diffuse), static_cast<const Bsdf*>(&metal)})
        for (const Vec3& wi : kIncident) {
            const SphereGrid grid{20, 40};
            std::vector<double> observed(grid.cells(), 0.0);
            const int n = 200000;
            Rng rng(11, 5);
            int valid = 0;
            for (int k = 0; k < n; ++k) {
                const BsdfSample s =
                    bsdf->sample(wi, {rng.uniform(), rng.uniform(), rng.uniform()});
                if (!s.valid()) continue;
                ++valid;
                observed[grid.cellOf(s.wo)] += 1;
                const BsdfEval e = bsdf->evalPdf(wi, s.wo);
                ASSERT_NEAR(s.pdf, e.pdf, 1e-9 * e.pdf);
                for (int c = 0; c < 3; ++c)
                    ASSERT_NEAR(s.weight[c], e.value[c] / e.pdf, 1e-9 * s.weight[c] + 1e-12);
            }
            const std::vector<double> expected =
                grid.expectedCounts([&](const Vec3& w) { return bsdf->pdf(wi, w); }, n);
            const Chi2Result r = chi2Test(observed, expected);
            EXPECT_GT(r.pValue, level) << wi << " chi2 " << r.statistic << " dof " << r.dof;
            EXPECT_GT(valid, n / 2);
        }
}

TEST(SurfaceBsdfs, ParametersAreValidated) {
    using weft::testing::expectInputError;
    expectInputError(
        [] {
            DiffuseBsdf({0.5, 1.5, 0.5}, "objects[0].material.reflectance");
        },
        {"objects[0].material.reflectance", "1.5", "[0, 1]"});
    expectInputError([] { ConductorBsdf(Rgb(0.5), 0.001, "objects[1].material"); },
                     {"objects[1].material.roughness", "0.001", "[0.01, 1]"});
    expectInputError(
        [] {
            ConductorBsdf({std::nan(""), 0, 0}, 0.5, "objects[1].material");
        },
        {"objects[1].material.colour", "[0, 1]"});
}

}  // namespace
}  // namespace weft::render
