// Tests for weft/core/sampling.h against independent truth: each sampler's
// chi-square against its pdf (core/chi2.h), each pdf integrated over the
// sphere by a midpoint rule, unit length and the documented mappings.
#include "weft/core/sampling.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "weft/core/chi2.h"
#include "weft/core/math.h"
#include "weft/core/rng.h"
#include "weft/core/test_util.h"

namespace weft {
namespace {

using testing::scaled;

// Each chi-square test passes at this level; the 5 of them give an overall 1%.
const double kChi2Level = sidakCorrectedLevel(0.01, 5);

using Sampler = std::function<Vec3(double, double)>;
using Pdf = std::function<double(const Vec3&)>;

// Chi-square of n samples on weft's sphere grid (an even number of phi bins,
// so that the grid's cells do not straddle the plane z = 0).
Chi2Result sphereChi2(const Sampler& sample, const Pdf& pdf, int64_t n, uint64_t seed) {
    const SphereGrid grid{16, 32};
    std::vector<double> observed(grid.cells(), 0.0);
    Rng rng(31, seed);
    for (int64_t k = 0; k < n; ++k) {
        const double u1 = rng.uniform(), u2 = rng.uniform();
        observed[grid.cellOf(sample(u1, u2))] += 1;
    }
    return chi2Test(observed, grid.expectedCounts(pdf, double(n)));
}

// Midpoint rule over the sphere in (theta, phi) about +z.
double integrateSphere(const Pdf& f, int thetaSteps = 400, int phiSteps = 400) {
    const double dTheta = kPi / thetaSteps, dPhi = kTwoPi / phiSteps;
    double sum = 0;
    for (int i = 0; i < thetaSteps; ++i) {
        const double theta = (i + 0.5) * dTheta, sinTheta = std::sin(theta);
        for (int j = 0; j < phiSteps; ++j) {
            const double phi = (j + 0.5) * dPhi;
            sum +=
                f({sinTheta * std::cos(phi), sinTheta * std::sin(phi), std::cos(theta)}) * sinTheta;
        }
    }
    return sum * dTheta * dPhi;
}

// Calls check(u1, u2, w) on samples at u on a grid including 0 and values near 1.
void forGridSamples(const Sampler& sample, const std::function<void(double, double, Vec3)>& check) {
    const double us[] = {0.0, 1e-12, 0.1, 0.25, 0.5, 0.75, 0.9, 1.0 - 1e-12, 0x1.fffffffffffffp-1};
    for (double u1 : us)
        for (double u2 : us) check(u1, u2, sample(u1, u2));
}

double azimuth(const Vec3& w) { return std::atan2(w.y, w.x); }

// The distance of azimuth a from b on the circle.
double azimuthError(double a, double b) { return std::fabs(wrapAngle(a - b)); }

TEST(Sampling, UniformSphere) {
    const Sampler sample = sampleUniformSphere;
    forGridSamples(sample, [](double u1, double u2, const Vec3& w) {
        EXPECT_NEAR(length(w), 1.0, 1e-12) << u1 << " " << u2;
        EXPECT_EQ(w.z, 1.0 - 2.0 * u1);
        if (w.z > -1 && w.z < 1) {
            EXPECT_LT(azimuthError(azimuth(w), kTwoPi * u2), 1e-6);
        }
    });
    EXPECT_DOUBLE_EQ(uniformSpherePdf(), 1.0 / (4.0 * kPi));
    const Pdf pdf = [](const Vec3&) { return uniformSpherePdf(); };
    EXPECT_NEAR(integrateSphere(pdf), 1.0, 1e-4);
    const Chi2Result r = sphereChi2(sample, pdf, scaled(200000), 1);
    EXPECT_GT(r.pValue, kChi2Level) << "chi2 " << r.statistic << " dof " << r.dof;
}

TEST(Sampling, UniformHemisphere) {
    const Sampler sample = sampleUniformHemisphere;
    forGridSamples(sample, [](double u1, double u2, const Vec3& w) {
        EXPECT_NEAR(length(w), 1.0, 1e-12) << u1 << " " << u2;
        EXPECT_GE(w.z, 0.0);
        EXPECT_EQ(w.z, u1);
        if (w.z < 1) {
            EXPECT_LT(azimuthError(azimuth(w), kTwoPi * u2 - kPi), 1e-6);
        }
    });
    // u2 = 0 is the azimuth -pi, u2 = 1/2 the azimuth 0.
    EXPECT_LT(sampleUniformHemisphere(0.5, 0.0).x, 0.0);
    EXPECT_GT(sampleUniformHemisphere(0.5, 0.5).x, 0.0);
    const Pdf pdf = [](const Vec3& w) { return w.z >= 0 ? uniformHemispherePdf() : 0.0; };
    EXPECT_DOUBLE_EQ(uniformHemispherePdf(), 1.0 / (2.0 * kPi));
    EXPECT_NEAR(integrateSphere(pdf), 1.0, 1e-4);
    const Chi2Result r = sphereChi2(sample, pdf, scaled(200000), 2);
    EXPECT_GT(r.pValue, kChi2Level) << "chi2 " << r.statistic << " dof " << r.dof;
}

TEST(Sampling, CosineHemisphere) {
    const Sampler sample = sampleCosineHemisphere;
    forGridSamples(sample, [](double u1, double u2, const Vec3& w) {
        EXPECT_NEAR(length(w), 1.0, 1e-12) << u1 << " " << u2;
        EXPECT_GE(w.z, 0.0);
        EXPECT_NEAR(w.z, std::sqrt(1.0 - u1), 1e-15);
        if (w.z < 1) {
            EXPECT_LT(azimuthError(azimuth(w), kTwoPi * u2), 1e-6);
        }
    });
    const Pdf pdf = [](const Vec3& w) { return w.z >= 0 ? cosineHemispherePdf(w.z) : 0.0; };
    EXPECT_NEAR(integrateSphere(pdf), 1.0, 1e-4);
    const Chi2Result r = sphereChi2(sample, pdf, scaled(200000), 3);
    EXPECT_GT(r.pValue, kChi2Level) << "chi2 " << r.statistic << " dof " << r.dof;
}

TEST(Sampling, UniformSphericalPatch) {
    // A patch straddling the azimuth 0 and one of the RDM's incident bins.
    struct Patch {
        double theta0, theta1, phi0, phi1;
    };
    const Patch patches[] = {{0.3, 1.1, -0.7, 0.4}, {kHalfPi * 7 / 8, kHalfPi, -kPi, -kPi + 0.2}};
    uint64_t seed = 4;
    for (const Patch& p : patches) {
        const auto sample = [&](double u1, double u2) {
            return sampleUniformSphericalPatch(p.theta0, p.theta1, p.phi0, p.phi1, u1, u2);
        };
        const double pdfValue = uniformSphericalPatchPdf(p.theta0, p.theta1, p.phi0, p.phi1);
        forGridSamples(sample, [&](double u1, double u2, const Vec3& w) {
            EXPECT_NEAR(length(w), 1.0, 1e-12) << u1 << " " << u2;
            const double theta = safeAcos(w.z);
            EXPECT_GE(theta, p.theta0 - 1e-9);
            EXPECT_LE(theta, p.theta1 + 1e-9);
            EXPECT_LT(azimuthError(azimuth(w), p.phi0 + u2 * (p.phi1 - p.phi0)), 1e-6);
        });
        // The pdf integrates to 1 over the patch (midpoint rule in theta).
        const int steps = 2000;
        const double dTheta = (p.theta1 - p.theta0) / steps;
        double integral = 0;
        for (int i = 0; i < steps; ++i)
            integral += pdfValue * std::sin(p.theta0 + (i + 0.5) * dTheta) * dTheta;
        EXPECT_NEAR(integral * (p.phi1 - p.phi0), 1.0, 1e-6);
        // Uniform in (cos theta, phi) over the patch: chi-square on a 10 x 10
        // grid of equal cells, each expecting n / 100.
        const int cells = 10;
        const int64_t n = scaled(100000);
        std::vector<double> observed(cells * cells, 0.0);
        Rng rng(41, seed++);
        const double c0 = std::cos(p.theta0), c1 = std::cos(p.theta1);
        for (int64_t k = 0; k < n; ++k) {
            const double u1 = rng.uniform(), u2 = rng.uniform();
            const Vec3 w = sample(u1, u2);
            const double s = (w.z - c0) / (c1 - c0);
            double phi = azimuth(w);
            if (phi < p.phi0 - 1e-9) phi += kTwoPi;
            const double t = (phi - p.phi0) / (p.phi1 - p.phi0);
            const int i = std::clamp(static_cast<int>(s * cells), 0, cells - 1);
            const int j = std::clamp(static_cast<int>(t * cells), 0, cells - 1);
            observed[i * cells + j] += 1;
        }
        const Chi2Result r =
            chi2Test(observed, std::vector<double>(observed.size(), double(n) / (cells * cells)));
        EXPECT_GT(r.pValue, kChi2Level) << "chi2 " << r.statistic << " dof " << r.dof;
    }
}

}  // namespace
}  // namespace weft
