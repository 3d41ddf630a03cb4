#include "weft/fit/calibration.h"

#include <gtest/gtest.h>

#include <cmath>

#include "weft/core/math.h"
#include "weft/core/rng.h"
#include "weft/fit/fit.h"
#include "weft/fit/metrics.h"
#include "weft/yarn/material_preset.h"
#include "weft/yarn/yarn_lobes.h"

namespace weft {
namespace {

Vec3 randomUpper(Rng& rng) {
    const double z = rng.uniform(), phi = kTwoPi * rng.uniform();
    const double s = std::sqrt(std::max(0.0, 1 - z * z));
    return {s * std::cos(phi), s * std::sin(phi), z};
}

// The basis spans every polynomial of the degree on the sphere, including
// those with x^2 and x^3 (reduced by x^2 = 1 - y^2 - z^2): a least-squares fit
// of such a polynomial is exact.
TEST(EnergyCalibration, BasisSpansPolynomialsOnTheSphere) {
    Rng rng(7, 1);
    for (int degree : {0, 1, 3, 6}) {
        auto target = [&](const Vec3& w) {
            // A full (non-reduced) polynomial of the degree in x, y, z.
            double v = 0.3;
            if (degree >= 1) v += 0.5 * w.x - 0.2 * w.z;
            if (degree >= 3) v += 0.7 * w.x * w.x * w.x - 0.4 * w.x * w.x * w.y + 0.3 * w.y * w.z;
            if (degree >= 6) v += 0.6 * std::pow(w.x, 6) - 0.5 * std::pow(w.x * w.y, 2) * w.z;
            return 0.5 * v;  // within the clamp of log s
        };
        std::vector<Vec3> wi;
        std::vector<double> y, weight;
        for (int k = 0; k < 400; ++k) {
            wi.push_back(randomUpper(rng));
            y.push_back(target(wi.back()));
            weight.push_back(0.5 + rng.uniform());
        }
        std::vector<double> f(static_cast<size_t>(EnergyCalibration::termCount(degree)));
        EnergyCalibration::basis(wi[0], degree, f.data());
        for (int a = 0; a <= std::min(degree, 1); ++a)
            for (int b = 0; a + b <= degree; ++b)
                for (int c = 0; a + b + c <= degree; ++c)
                    EXPECT_DOUBLE_EQ(f[EnergyCalibration::termIndex(a, b, c, degree)],
                                     std::pow(wi[0].x, a) * std::pow(wi[0].y, b) * std::pow(wi[0].z, c));
        const std::vector<double> c = fitLogPolynomial(wi, y, weight, degree);
        ASSERT_EQ(c.size(), static_cast<size_t>(EnergyCalibration::termCount(degree)));
        EnergyCalibration cal;
        cal.degree = degree;
        for (int ch = 0; ch < 3; ++ch) cal.r[ch] = c, cal.m[ch] = std::vector<double>(c.size(), 0.0);
        for (int k = 0; k < 50; ++k) {
            const Vec3 w = randomUpper(rng);
            EXPECT_NEAR(std::log(cal.scales(w).r.g), target(w), 1e-8) << degree;
            EXPECT_DOUBLE_EQ(cal.scales(w).m.b, 1.0);
        }
    }
}

// fitEnergyCalibration against an RDM made from a model times known scales.
// (1) With no scale, the fitted scales are 1 up to the difference between the
// synthetic RDM's bin sums of point values and the quadrature integral (up to
// 12% for R, whose lobe is 2-4 bins wide; a gathered RDM holds bin averages,
// whose sums are the exact integral). (2) The fit is linear in log space, so the scales fitted
// with a known scale divided by those fitted without are the known scale.
TEST(EnergyCalibration, FitRecoversKnownScales) {
    const RdmBins bins{8, 24, 45, 90};
    const MaterialPreset& fleece = findMaterialPreset("fleece");
    RdmData rdm;
    rdm.dir = "synthetic";
    rdm.bins = bins;
    rdm.count.assign(bins.incidentCount(), 1000);
    YarnModel model;
    model.fiber = fleece.fiber;
    model.tNet = NetworkWeights::initialised({3, 3, 1}, OutputFunction::Sigmoid, 2);
    model.mNet = NetworkWeights::initialised({6, 5, 3}, OutputFunction::Exp, 3);
    model.rLobe.tiltDeg = SurfaceFiberFrame::tiltDegOfTwist(fleece.ply.twist);
    rdm.pT = modelTransmissionMap(model, bins);
    rdm.rdmR = modelReflectionMap(model, bins);
    rdm.rdmM = modelMultipleScatteringMap(model, bins);
    const EnergyCalibration identity = fitEnergyCalibration(model, rdm, 2, 2);
    ASSERT_EQ(identity.degree, 2);

    YarnModel scaled = model;
    scaled.calibration.degree = 2;
    for (int c = 0; c < 3; ++c) {
        scaled.calibration.r[c] = std::vector<double>(9, 0.0);
        scaled.calibration.m[c] = std::vector<double>(9, 0.0);
        scaled.calibration.r[c][0] = 0.2 - 0.1 * c;  // constant
        scaled.calibration.r[c][2] = 0.4;            // z^2 (order: a = 0, b = 0, c = 0..2)
        scaled.calibration.m[c][1] = -0.3;           // z
        scaled.calibration.m[c][6] = 0.25 * c;       // x (a = 1, b = 0, c = 0)
    }
    rdm.rdmR = modelReflectionMap(scaled, bins);
    rdm.rdmM = modelMultipleScatteringMap(scaled, bins);
    nlohmann::json summary;
    const EnergyCalibration fitted = fitEnergyCalibration(model, rdm, 2, 1, &summary);
    double worstIdentityR = 0, worstIdentityM = 0;
    for (size_t i = 0; i < bins.incidentCount(); ++i) {
        const Vec3 wi = bins.incidentCentre(i);
        const auto id = identity.scales(wi), f = fitted.scales(wi), truth = scaled.calibration.scales(wi);
        for (int c = 0; c < 3; ++c) {
            worstIdentityR = std::max(worstIdentityR, std::fabs(id.r[c] - 1));
            worstIdentityM = std::max(worstIdentityM, std::fabs(id.m[c] - 1));
            EXPECT_NEAR(f.r[c] / id.r[c], truth.r[c], 0.03 * truth.r[c]) << i << " " << c;
            EXPECT_NEAR(f.m[c] / id.m[c], truth.m[c], 1e-4 * truth.m[c]) << i << " " << c;
        }
    }
    EXPECT_LT(worstIdentityM, 0.01);
    EXPECT_LT(worstIdentityR, 0.2);
    EXPECT_EQ(summary.at("degree"), 2);
    EXPECT_LT(summary.at("albedo_rel_error_mean_abs_after")[1].get<double>(), 0.01);
    std::printf("identity fit: worst |s - 1| R %.4f M %.4f\n", worstIdentityR, worstIdentityM);
}

}  // namespace
}  // namespace weft
