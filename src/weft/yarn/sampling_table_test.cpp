#include "weft/yarn/sampling_table.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "weft/core/chi2.h"
#include "weft/core/math.h"
#include "weft/core/test_util.h"

namespace weft {
namespace {

// A test function with the yarn's kinds of features, in the surface fiber
// frame: a narrow band on the specular cone z_o = -z_i, a forward lobe
// around -wi and a broad floor, so that it is neither separable nor smooth.
double testFunction(const SurfaceFiberFrame& frame, const Vec3& wi, const Vec3& wo) {
    const Vec3 i = frame.toLocal(wi), o = frame.toLocal(wo);
    const double cone = std::exp(-sqr((o.x + i.x) / 0.05)) * (1.5 + std::cos(std::atan2(o.y, o.z)));
    const double forward = std::exp(8.0 * (dot(wo, -wi) - 1.0));
    return 2.0 * cone + 3.0 * forward + 0.05;
}

const SurfaceFiberFrame& testFrame() {
    static const SurfaceFiberFrame frame = SurfaceFiberFrame::fromTiltDeg(25);
    return frame;
}

const SamplingTable& testTable() {
    static const SamplingTable table(
        testFrame(), 1,
        [](const Vec3& wi, const std::vector<Vec3>& wo, std::vector<double>& values) {
            for (size_t k = 0; k < wo.size(); ++k) values[k] = testFunction(testFrame(), wi, wo[k]);
        });
    return table;
}

// Upper-hemisphere directions at nodes, between nodes and near the edges.
std::vector<Vec3> incidentDirections() {
    return {
        sphericalDirection(radians(3), radians(20)), sphericalDirection(radians(45), radians(-60)),
        sphericalDirection(radians(87), radians(100)), sphericalDirection(radians(60), radians(5)),
        SamplingTable::nodeDirection(testFrame(), 7, 11)};
}

// The integral of g over the sphere by the midpoint rule on a fine (z, phi) grid.
template <typename G>
double sphereIntegral(const G& g, int rows = 1500, int columns = 1000) {
    double sum = 0;
    for (int a = 0; a < rows; ++a) {
        const double z = -1 + (a + 0.5) * 2.0 / rows, r = std::sqrt(1 - z * z);
        for (int b = 0; b < columns; ++b) {
            const double phi = -kPi + (b + 0.5) * kTwoPi / columns;
            sum += g(Vec3{r * std::cos(phi), r * std::sin(phi), z});
        }
    }
    return sum * (2.0 / rows) * (kTwoPi / columns);
}

TEST(SamplingTable, PdfIsPositiveAndIntegratesToOne) {
    const SamplingTable& table = testTable();
    for (const Vec3& wi : incidentDirections()) {
        const SamplingTable::Layout in = table.layout(wi);
        double smallest = 1e300;
        const double integral = sphereIntegral([&](const Vec3& wo) {
            const double p = table.pdf(in, wo);
            smallest = std::min(smallest, p);
            return p;
        });
        EXPECT_NEAR(integral, 1.0, 2e-3) << wi;
        EXPECT_GT(smallest, 0.0) << wi;
    }
}

TEST(SamplingTable, SamplingIsChiSquareConsistentWithPdf) {
    const SamplingTable& table = testTable();
    const std::vector<Vec3> directions = incidentDirections();
    const double alpha = sidakCorrectedLevel(0.01, static_cast<int>(directions.size()));
    const SphereGrid grid{60, 60};
    for (const Vec3& wi : directions) {
        const SamplingTable::Layout in = table.layout(wi);
        const int64_t n = testing::scaled(300000);
        std::vector<double> observed(grid.cells(), 0);
        Rng rng(3, static_cast<uint64_t>(1e6 * (wi.x + 2 * wi.y + 3 * wi.z) + 1e7));
        for (int64_t k = 0; k < n; ++k) {
            const Vec3 wo = table.sample(in, rng.uniform(), rng.uniform(), rng.uniform());
            ASSERT_NEAR(length(wo), 1.0, 1e-12);
            observed[grid.cellOf(wo)] += 1;
        }
        const std::vector<double> expected = grid.expectedCounts(
            [&](const Vec3& wo) { return table.pdf(in, wo); }, static_cast<double>(n));
        const Chi2Result r = chi2Test(observed, expected);
        std::printf("wi %g %g %g: chi2 %.1f, dof %d, p %.3g\n", wi.x, wi.y, wi.z, r.statistic,
                    r.dof, r.pValue);
        EXPECT_GT(r.pValue, alpha) << wi;
    }
}

// The table follows its function: the weight f / pdf of an estimator of the
// integral of f has a second moment close to the square of its mean, at
// nodes and between them (a wrong cell index or row layout would not).
TEST(SamplingTable, WeightOfItsFunctionStaysNearItsIntegral) {
    const SamplingTable& table = testTable();
    for (const Vec3& wi : incidentDirections()) {
        const SamplingTable::Layout in = table.layout(wi);
        double largest = 0;
        const double integral =
            sphereIntegral([&](const Vec3& wo) { return testFunction(testFrame(), wi, wo); });
        const double second = sphereIntegral([&](const Vec3& wo) {
            const double f = testFunction(testFrame(), wi, wo), p = table.pdf(in, wo);
            largest = std::max(largest, f / p);
            return f * f / p;
        });
        const double ratio = second / (integral * integral);
        std::printf("wi %g %g %g: E[w^2] / E[w]^2 %.4f, largest w / E[w] %.3f\n", wi.x, wi.y, wi.z,
                    ratio, largest / integral);
        EXPECT_LT(ratio, 1.1) << wi;
        EXPECT_LT(largest / integral, 3.0) << wi;
    }
}

TEST(SamplingTable, SizeIsUnderOneMegabyte) {
    EXPECT_LT(testTable().bytes(), 1u << 20);
    EXPECT_EQ(
        testTable().bytes(),
        static_cast<size_t>(SamplingTable::kNodes) *
            (SamplingTable::kCells + (SamplingTable::kRows + 1) * sizeof(float) + sizeof(double)));
}

}  // namespace
}  // namespace weft
