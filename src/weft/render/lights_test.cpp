#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "weft/core/chi2.h"
#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/image_io.h"
#include "weft/core/math.h"
#include "weft/core/rng.h"
#include "weft/core/test_util.h"
#include "weft/render/constant_light.h"
#include "weft/render/delta_lights.h"
#include "weft/render/environment_light.h"
#include "weft/render/sphere_light.h"

namespace weft::render {
namespace {

using testing::expectInputError;
using testing::scaled;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Each chi-square test passes at this level; ~10 of them give an overall 1%.
const double kChi2Level = sidakCorrectedLevel(0.01, 10);

// ---------------------------------------------------------------------------
// The documented conventions, written out independently of lights.cpp.

// The direction of lat-long angles: theta from +y, phi such that
// u = phi / (2 pi) = atan2(d.x, -d.z) / (2 pi) (lights.h).
Vec3 latLong(double theta, double phi) {
    return {std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi)};
}

// The centre direction of texel (x, y) of a w x h lat-long image.
Vec3 texelCentre(int x, int y, int w, int h) {
    return latLong(kPi * (y + 0.5) / h, kTwoPi * (x + 0.5) / w);
}

// R_y(deg) as documented: +z turns towards +x.
Vec3 rotY(const Vec3& d, double deg) {
    const double a = radians(deg);
    return {d.x * std::cos(a) + d.z * std::sin(a), d.y, -d.x * std::sin(a) + d.z * std::cos(a)};
}

double lum(const Rgb& c) { return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b; }

// A test image with varied texels, a black row and a few black texels.
Image randomImage(int w, int h, uint64_t seed) {
    Rng rng(7, seed);
    Image image(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            Rgb c(0.05 + 2 * rng.uniform(), 0.05 + rng.uniform(), 0.05 + 3 * rng.uniform());
            if (y == 1 || (x + 3 * y) % 7 == 0) c = Rgb(0);
            image.set(x, y, c);
        }
    image.set(w / 2, h / 2, Rgb(20, 15, 10));  // a bright spot
    return image;
}

// Midpoint rule over the sphere in (theta, phi) about the pole `n` of frame.
double integrateSphere(const std::function<double(const Vec3&)>& f, int thetaSteps, int phiSteps,
                       const Frame& frame = Frame::fromZ({0, 1, 0})) {
    const double dTheta = kPi / thetaSteps, dPhi = kTwoPi / phiSteps;
    double sum = 0;
    for (int i = 0; i < thetaSteps; ++i) {
        const double theta = (i + 0.5) * dTheta, sinTheta = std::sin(theta);
        double row = 0;
        for (int j = 0; j < phiSteps; ++j) {
            const double phi = (j + 0.5) * dPhi;
            row += f(frame.fromLocal(
                {sinTheta * std::cos(phi), sinTheta * std::sin(phi), std::cos(theta)}));
        }
        sum += row * sinTheta;
    }
    return sum * dTheta * dPhi;
}

// Chi-square test of an infinite light's samples on a lat-long grid of the
// unrotated map (thetaBins x phiBins), whose bins subdivide the texels so
// that the piecewise-constant pdf times sin theta is constant on each; the
// expected counts integrate pdf() with nodes x nodes midpoints per bin.
Chi2Result latLongChi2(const Light& light, double rotateDeg, int thetaBins, int phiBins, int nodes,
                       int64_t n, uint64_t seed) {
    std::vector<double> observed(thetaBins * phiBins, 0.0), expected(observed.size(), 0.0);
    Rng rng(11, seed);
    int64_t invalid = 0;
    for (int64_t k = 0; k < n; ++k) {
        const LightSample s = light.sample({0, 0, 0}, {rng.uniform(), rng.uniform()});
        if (!s.valid()) {
            ++invalid;
            continue;
        }
        const Vec3 m = rotY(s.wi, -rotateDeg);
        const double theta = safeAcos(m.y);
        double phi = std::atan2(m.x, -m.z);
        if (phi < 0) phi += kTwoPi;
        const int i = std::min(thetaBins - 1, static_cast<int>(theta / kPi * thetaBins));
        const int j = std::min(phiBins - 1, static_cast<int>(phi / kTwoPi * phiBins));
        observed[i * phiBins + j] += 1;
    }
    EXPECT_EQ(invalid, 0);
    const double dTheta = kPi / thetaBins / nodes, dPhi = kTwoPi / phiBins / nodes;
    for (int i = 0; i < thetaBins; ++i)
        for (int j = 0; j < phiBins; ++j) {
            double sum = 0;
            for (int a = 0; a < nodes; ++a)
                for (int b = 0; b < nodes; ++b) {
                    const double theta = (i * nodes + a + 0.5) * dTheta;
                    const double phi = (j * nodes + b + 0.5) * dPhi;
                    sum += light.pdf({0, 0, 0}, rotY(latLong(theta, phi), rotateDeg)) *
                           std::sin(theta);
                }
            expected[i * phiBins + j] = sum * dTheta * dPhi * n;
        }
    return chi2Test(observed, expected);
}

// Chi-square test on weft's sphere grid in a frame whose pole (+x of the grid)
// is `axis`, for any light seen from p.
Chi2Result frameChi2(const Light& light, const Vec3& p, const Vec3& axis, int thetaBins,
                     int phiBins, int64_t n, uint64_t seed) {
    const Frame frame = Frame::fromX(axis);
    const SphereGrid grid{thetaBins, phiBins};
    std::vector<double> observed(grid.cells(), 0.0);
    Rng rng(13, seed);
    for (int64_t k = 0; k < n; ++k) {
        const LightSample s = light.sample(p, {rng.uniform(), rng.uniform()});
        EXPECT_TRUE(s.valid());
        if (s.valid()) observed[grid.cellOf(frame.toLocal(s.wi))] += 1;
    }
    const auto expected = grid.expectedCounts(
        [&](const Vec3& w) { return light.pdf(p, frame.fromLocal(w)); }, double(n));
    return chi2Test(observed, expected);
}

// Monte Carlo estimate of the integral of radiance(w) f(w) over the sphere by
// light sampling, per channel, and the standard error of the luminance.
struct Estimate {
    Rgb mean;
    double lumStdErr = 0;
};
Estimate estimateByLightSampling(const Light& light, const Vec3& p,
                                 const std::function<double(const Vec3&)>& f, int64_t n,
                                 uint64_t seed) {
    Rng rng(17, seed);
    Rgb sum;
    double lumSum = 0, lumSum2 = 0;
    for (int64_t k = 0; k < n; ++k) {
        const LightSample s = light.sample(p, {rng.uniform(), rng.uniform()});
        if (!s.valid()) continue;
        const Rgb v = s.radiance * (f(s.wi) / s.pdf);
        sum += v;
        lumSum += lum(v);
        lumSum2 += lum(v) * lum(v);
    }
    const double mean = lumSum / n;
    return {sum / double(n), std::sqrt(std::max(0.0, lumSum2 / n - mean * mean) / n)};
}

// The same integral for a lat-long image: the sum over texels of the texel's
// radiance times the integral of f over the texel (nodes x nodes midpoints),
// using only the documented convention (not the light's lookup).
Rgb latLongIntegral(const Image& image, double scale, double rotateDeg,
                    const std::function<double(const Vec3&)>& f, int nodes) {
    const int w = image.width, h = image.height;
    const double dTheta = kPi / h / nodes, dPhi = kTwoPi / w / nodes;
    Rgb sum;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double integral = 0;
            for (int a = 0; a < nodes; ++a)
                for (int b = 0; b < nodes; ++b) {
                    const double theta = (y * nodes + a + 0.5) * dTheta;
                    const double phi = (x * nodes + b + 0.5) * dPhi;
                    integral += f(rotY(latLong(theta, phi), rotateDeg)) * std::sin(theta);
                }
            sum += image.get(x, y) * (integral * dTheta * dPhi);
        }
    return sum * scale;
}

const std::vector<std::pair<const char*, std::function<double(const Vec3&)>>>& testIntegrands() {
    static const std::vector<std::pair<const char*, std::function<double(const Vec3&)>>> fs = {
        {"one", [](const Vec3&) { return 1.0; }},
        {"cosine",
         [](const Vec3& w) {
             return std::max(0.0, dot(normalize({0.2, 1, 0.4}), w));
         }},
        {"exp",
         [](const Vec3& w) {
             return std::exp(2 * dot(normalize({1, 0.3, -0.5}), w));
         }},
    };
    return fs;
}

void expectRgbNear(const Rgb& a, const Rgb& b, double tol, const std::string& what) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], tol) << what << " channel " << c;
}

// ---------------------------------------------------------------------------
// ConstantLight

TEST(ConstantLight, SamplesAreUniformWithTheDocumentedPdfAndRadiance) {
    const ConstantLight light(Rgb(0.5, 1.0, 2.0));
    EXPECT_TRUE(light.isInfinite());
    EXPECT_LT(light.intersect({0, 0, 0}, {0, 0, 1}, kInf), 0);
    Rng rng(1, 1);
    for (int k = 0; k < 1000; ++k) {
        const Vec3 p{rng.uniform(), rng.uniform(), rng.uniform()};
        const LightSample s = light.sample(p, {rng.uniform(), rng.uniform()});
        ASSERT_TRUE(s.valid());
        EXPECT_NEAR(length(s.wi), 1.0, 1e-12);
        EXPECT_DOUBLE_EQ(s.pdf, 1.0 / (4 * kPi));
        EXPECT_EQ(s.pdf, light.pdf(p, s.wi));
        EXPECT_EQ(s.radiance, Rgb(0.5, 1.0, 2.0));
        EXPECT_EQ(s.radiance, light.radiance(s.wi));
        EXPECT_EQ(s.distance, kInf);
    }
    const Chi2Result r = frameChi2(light, {0, 0, 0}, {0, 1, 0}, 10, 20, scaled(200000), 2);
    EXPECT_GT(r.pValue, kChi2Level) << "chi2 " << r.statistic << " dof " << r.dof;
    EXPECT_NEAR(integrateSphere([&](const Vec3& w) { return light.pdf({}, w); }, 200, 400), 1.0,
                1e-4);
}

TEST(ConstantLight, RejectsBadRadiance) {
    for (const Rgb& bad : {Rgb(kNaN, 1, 1), Rgb(1, -0.5, 1), Rgb(1, 1, kInf)})
        expectInputError([&] { ConstantLight light(bad); }, {"constant light", "radiance"});
    EXPECT_NO_THROW(ConstantLight(Rgb(0)));
}

// ---------------------------------------------------------------------------
// EnvironmentLight: conventions

TEST(EnvironmentLight, RadianceAtTexelCentresFollowsTheLatLongConvention) {
    const int w = 8, h = 4;
    Image image(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) image.set(x, y, Rgb(1 + x + 10 * y, 100 + y, 200 + x));
    const EnvironmentLight light(image, 2.0, 0.0, "unique.exr");
    EXPECT_TRUE(light.isInfinite());
    EXPECT_LT(light.intersect({0, 0, 0}, {0, 1, 0}, kInf), 0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const Rgb want = Rgb(1 + x + 10 * y, 100 + y, 200 + x) * 2.0;
            EXPECT_EQ(light.radiance(texelCentre(x, y, w, h)), want) << x << ", " << y;
            // Anywhere inside the texel, not only at its centre.
            for (double fx : {0.05, 0.95})
                for (double fy : {0.05, 0.95})
                    EXPECT_EQ(light.radiance(latLong(kPi * (y + fy) / h, kTwoPi * (x + fx) / w)),
                              want);
        }
    // Landmarks: +y is row 0, -y the last row; -z is column 0 (u = 0), +z the
    // boundary between the two middle columns, +x a quarter of the way (u = 1/4).
    EXPECT_EQ(light.radiance({0, 1, 0}).g, 2.0 * 100);
    EXPECT_EQ(light.radiance({0, -1, 0}).g, 2.0 * (100 + h - 1));
    EXPECT_EQ(light.radiance(normalize({0.01, 0.2, -1})).b, 2.0 * 200);
    EXPECT_EQ(light.radiance(normalize({1, 0.2, -0.01})).b, 2.0 * (200 + w / 4 - 1));
    EXPECT_EQ(light.radiance(normalize({1, 0.2, 0.01})).b, 2.0 * (200 + w / 4));
}

TEST(EnvironmentLight, RotationTurnsTheMapAboutPlusY) {
    const int w = 8, h = 4;
    Image image(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) image.set(x, y, Rgb(1 + x + 10 * y));
    // rotate_deg 90: the map direction (x, y, z) appears at (z, y, -x); texel
    // (4, 1), just past +z in the unrotated map, appears just past +x.
    const EnvironmentLight rotated90(image, 1.0, 90.0, "rot90");
    const Vec3 m = texelCentre(4, 1, w, h);
    EXPECT_GT(m.z, 0.5);
    EXPECT_EQ(rotated90.radiance({m.z, m.y, -m.x}).r, 1 + 4 + 10);
    for (double deg : {90.0, 37.5, -120.0, 400.0}) {
        const EnvironmentLight light(image, 1.0, deg, "rot");
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                EXPECT_EQ(light.radiance(rotY(texelCentre(x, y, w, h), deg)).r, 1 + x + 10 * y)
                    << "rotate_deg " << deg << " texel " << x << ", " << y;
    }
}

TEST(EnvironmentLight, PdfIsLuminanceTimesRowSineOverSinTheta) {
    const int w = 16, h = 8;
    const Image image = randomImage(w, h, 3);
    for (double deg : {0.0, 37.0}) {
        const EnvironmentLight light(image, 1.5, deg, "random");
        double total = 0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                total += lum(image.get(x, y)) * std::sin(kPi * (y + 0.5) / h);
        Rng rng(5, 5);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const double theta = kPi * (y + 0.1 + 0.8 * rng.uniform()) / h;
                const double phi = kTwoPi * (x + 0.1 + 0.8 * rng.uniform()) / w;
                const double pdfUv =
                    lum(image.get(x, y)) * std::sin(kPi * (y + 0.5) / h) * w * h / total;
                const double want = pdfUv / (2 * kPi * kPi * std::sin(theta));
                EXPECT_NEAR(light.pdf({1, 2, 3}, rotY(latLong(theta, phi), deg)), want,
                            1e-12 * want)
                    << "texel " << x << ", " << y;
            }
    }
}

// ---------------------------------------------------------------------------
// EnvironmentLight: sampling

TEST(EnvironmentLight, SampleAgreesWithPdfAndRadiance) {
    const EnvironmentLight light(randomImage(16, 8, 4), 1.5, 37.0, "random");
    Rng rng(6, 6);
    for (int k = 0; k < 20000; ++k) {
        const Vec3 p{rng.uniform(), rng.uniform(), rng.uniform()};
        const LightSample s = light.sample(p, {rng.uniform(), rng.uniform()});
        ASSERT_TRUE(s.valid());
        EXPECT_NEAR(length(s.wi), 1.0, 1e-12);
        EXPECT_EQ(s.pdf, light.pdf(p, s.wi));
        EXPECT_EQ(s.radiance, light.radiance(s.wi));
        EXPECT_FALSE(s.radiance.isBlack());  // black texels are never sampled
        EXPECT_EQ(s.distance, kInf);
    }
    // Extreme sample values stay valid.
    for (double u0 : {0.0, 0.5, 1.0 - 1e-16})
        for (double u1 : {0.0, 1e-300, 0.5, 1.0 - 1e-16}) {
            const LightSample s = light.sample({}, {u0, u1});
            if (s.valid()) {
                EXPECT_TRUE(std::isfinite(s.pdf) && isFinite(s.wi));
            }
        }
}

TEST(EnvironmentLight, SamplesFollowPdfChiSquare) {
    const Image image = randomImage(16, 8, 7);
    for (double deg : {0.0, 37.0}) {
        const EnvironmentLight light(image, 1.0, deg, "random");
        const Chi2Result r = latLongChi2(light, deg, 16, 32, 2, scaled(500000), 8);
        EXPECT_GT(r.pValue, kChi2Level)
            << "rotate " << deg << ": chi2 " << r.statistic << " dof " << r.dof;
    }
}

TEST(EnvironmentLight, PdfIntegratesToOne) {
    for (double deg : {0.0, 37.0}) {
        const EnvironmentLight light(randomImage(16, 8, 9), 1.0, deg, "random");
        const double integral =
            integrateSphere([&](const Vec3& w) { return light.pdf({}, w); }, 800, 1600);
        EXPECT_NEAR(integral, 1.0, 2e-3) << "rotate " << deg;
    }
}

TEST(EnvironmentLight, LightSamplingEstimatesMatchQuadrature) {
    const Image image = randomImage(16, 8, 10);
    const EnvironmentLight light(image, 0.7, 37.0, "random");
    for (const auto& [name, f] : testIntegrands()) {
        const Rgb want = latLongIntegral(image, 0.7, 37.0, f, 8);
        const Estimate e = estimateByLightSampling(light, {}, f, scaled(200000), 11);
        const double tol = 5 * e.lumStdErr + 1e-3 * lum(want);
        EXPECT_NEAR(lum(e.mean), lum(want), tol) << name;
        expectRgbNear(e.mean, want, 3 * tol, name);
    }
}

TEST(EnvironmentLight, BlackImageOrZeroScaleGivesNoSamples) {
    Image black(8, 4);
    const Image bright = randomImage(8, 4, 12);
    for (const EnvironmentLight& light :
         {EnvironmentLight(black, 1.0, 0.0, "black"), EnvironmentLight(bright, 0.0, 10.0, "s0")}) {
        Rng rng(8, 8);
        for (int k = 0; k < 200; ++k) {
            const LightSample s = light.sample({}, {rng.uniform(), rng.uniform()});
            EXPECT_FALSE(s.valid());
            EXPECT_EQ(s.pdf, 0);
            const Vec3 d = normalize({rng.uniform() - 0.5, rng.uniform() - 0.5, 0.3});
            EXPECT_EQ(light.pdf({}, d), 0);
            EXPECT_TRUE(light.radiance(d).isBlack());
        }
    }
}

TEST(EnvironmentLight, SingleBrightTexelGetsEverySample) {
    Image image(8, 4);
    image.set(5, 2, Rgb(3, 2, 1));
    const EnvironmentLight light(image, 1.0, 0.0, "one texel");
    Rng rng(9, 9);
    for (int k = 0; k < 2000; ++k) {
        const LightSample s = light.sample({}, {rng.uniform(), rng.uniform()});
        ASSERT_TRUE(s.valid());
        EXPECT_EQ(s.radiance, Rgb(3, 2, 1));
        // The density is uniform in (u, v): 1 / (texel area in uv) / (2 pi^2 sin theta).
        const double sinTheta = std::sqrt(s.wi.x * s.wi.x + s.wi.z * s.wi.z);
        EXPECT_NEAR(s.pdf, 32.0 / (2 * kPi * kPi * sinTheta), 1e-9 * s.pdf);
    }
    EXPECT_NEAR(integrateSphere([&](const Vec3& w) { return light.pdf({}, w); }, 400, 800), 1.0,
                2e-3);
}

TEST(EnvironmentLight, RejectsBadImagesAndParameters) {
    Image good(4, 2);
    good.set(1, 1, Rgb(1));
    for (double bad : {kNaN, -1e-3, kInf}) {
        Image image = good;
        image.set(2, 1, Rgb(0.5, bad, 0.5));
        expectInputError([&] { EnvironmentLight(image, 1, 0, "sky.exr"); },
                         {"sky.exr", "texel (x 2, y 1)", "channel G"});
        expectInputError([&] { EnvironmentLight(good, bad, 0, "sky.exr"); }, {"sky.exr", "scale"});
    }
    for (double bad : {kNaN, kInf, -kInf})
        expectInputError([&] { EnvironmentLight(good, 1, bad, "sky.exr"); },
                         {"sky.exr", "rotate_deg"});
    expectInputError([] { EnvironmentLight(Image(), 1, 0, "empty.hdr"); }, {"empty.hdr"});
    Image wrongSize(4, 2);
    wrongSize.pixels.pop_back();
    expectInputError([&] { EnvironmentLight(wrongSize, 1, 0, "short.hdr"); }, {"short.hdr"});
}

// ---------------------------------------------------------------------------
// The procedural sky

Rgb documentedSky(const Vec3& d) {
    // docs/scene-format.md, "Procedural sky".
    const Rgb Z(0.25, 0.45, 0.90), H(1.00, 0.97, 0.92), G(0.2, 0.2, 0.2), C(0.8, 0.7, 0.5);
    const Vec3 s{0, std::sin(radians(30)), std::cos(radians(30))};
    const double y = d.y;
    const Rgb base = y >= 0 ? Z + (H - Z) * std::pow(1 - y, 3) : G + (H - G) * std::pow(1 + y, 8);
    return base + C * std::pow((1 + dot(d, s)) / 2, 32);
}

TEST(Sky, RadianceFollowsTheDocumentedFormula) {
    Rng rng(10, 10);
    for (int k = 0; k < 2000; ++k) {
        const double z = 2 * rng.uniform() - 1, phi = kTwoPi * rng.uniform();
        const Vec3 d{std::sqrt(1 - z * z) * std::cos(phi), z, std::sqrt(1 - z * z) * std::sin(phi)};
        expectRgbNear(skyRadiance(d), documentedSky(d), 1e-12, "random direction");
        EXPECT_GT(lum(skyRadiance(d)), 0.19);
        EXPECT_LT(lum(skyRadiance(d)), 1.25);
    }
    const Rgb zenith = skyRadiance({0, 1, 0}), nadir = skyRadiance({0, -1, 0});
    EXPECT_TRUE(zenith.b > zenith.g && zenith.g > zenith.r);  // bluish
    EXPECT_NEAR(nadir.r, 0.2, 1e-6);
    EXPECT_EQ(nadir.r, nadir.b);  // neutral ground
    const Rgb horizon = skyRadiance({0, 0, -1});
    EXPECT_GT(std::min({horizon.r, horizon.g, horizon.b}), 0.9);  // whitish
    // Continuous at the horizon, brightest towards the glow.
    expectRgbNear(skyRadiance(normalize({1, 1e-9, 0})), skyRadiance(normalize({1, -1e-9, 0})), 1e-7,
                  "horizon");
    EXPECT_NEAR(lum(skyRadiance({0, 0.5, std::sqrt(0.75)})), 1.2134, 1e-3);
}

// The sky's radiance is the formula at the exact direction, not the nearest
// texel: equal to the documented sky everywhere (texel edges included), and
// without the steps of a nearest-texel lookup (about 0.02-0.3 between rows of
// the 256 x 128 map) along a meridian walked in 1e-4 radian steps.
TEST(Sky, RadianceIsTheFormulaEverywhere) {
    const EnvironmentLight sky = skyLight(2.0);
    Rng rng(9, 9);
    for (int k = 0; k < 2000; ++k) {
        const Vec3 d = latLong(kPi * rng.uniform(), kTwoPi * rng.uniform());
        expectRgbNear(sky.radiance(d), documentedSky(d) * 2.0, 1e-12, "sky");
    }
    double largestStep = 0;
    Rgb previous = sky.radiance(latLong(0, 0.3));
    for (double theta = 1e-4; theta < kPi; theta += 1e-4) {
        const Rgb here = sky.radiance(latLong(theta, 0.3));
        for (int c = 0; c < 3; ++c)
            largestStep = std::max(largestStep, std::fabs(here[c] - previous[c]));
        previous = here;
    }
    EXPECT_LT(largestStep, 5e-3);
    // Sampling still draws from the texels' density, and a sample carries
    // the radiance of its exact direction.
    for (int k = 0; k < 200; ++k) {
        const LightSample s = sky.sample({0, 0, 0}, {rng.uniform(), rng.uniform()});
        ASSERT_TRUE(s.valid());
        EXPECT_EQ(s.radiance, sky.radiance(s.wi));
        EXPECT_EQ(s.pdf, sky.pdf({0, 0, 0}, s.wi));
    }
}

TEST(Sky, ImageHoldsTheFormulaAtTexelCentres) {
    const Image image = skyImage(32, 16);
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 32; ++x) {
            const Rgb want = documentedSky(texelCentre(x, y, 32, 16));
            expectRgbNear(image.get(x, y), want, 1e-6, "texel");
        }
    const EnvironmentLight sky = skyLight(2.0);
    EXPECT_EQ(sky.image().width, 256);
    EXPECT_EQ(sky.image().height, 128);
    const Vec3 d = texelCentre(100, 30, 256, 128);
    expectRgbNear(sky.radiance(d), documentedSky(d) * 2.0, 1e-5, "scaled sky");
    expectInputError([] { skyImage(0, 8); }, {"procedural sky"});
    expectInputError([] { skyLight(1.0, 8, -1); }, {"procedural sky"});
    expectInputError([] { skyLight(-1.0); }, {"procedural sky", "scale"});
    expectInputError([] { skyLight(kNaN); }, {"procedural sky", "scale"});
}

TEST(Sky, SamplingMatchesPdfAndQuadrature) {
    const EnvironmentLight sky = skyLight();
    // Bins of 8 x 8 texels, one quadrature node at each texel centre.
    const Chi2Result r = latLongChi2(sky, 0.0, 16, 32, 8, scaled(500000), 12);
    EXPECT_GT(r.pValue, kChi2Level) << "chi2 " << r.statistic << " dof " << r.dof;
    EXPECT_NEAR(integrateSphere([&](const Vec3& w) { return sky.pdf({}, w); }, 1024, 2048), 1.0,
                1e-3);
    for (const auto& [name, f] : testIntegrands()) {
        const Rgb want = latLongIntegral(sky.image(), 1.0, 0.0, f, 2);
        const Estimate e = estimateByLightSampling(sky, {}, f, scaled(200000), 13);
        const double tol = 5 * e.lumStdErr + 1e-3 * lum(want);
        EXPECT_NEAR(lum(e.mean), lum(want), tol) << name;
        expectRgbNear(e.mean, want, 3 * tol, name);
    }
    // The sky is not constant: the cosine integral about +y differs from
    // the one about -y by far more than the tolerance.
    const auto up = [](const Vec3& w) { return std::max(0.0, w.y); };
    const auto down = [](const Vec3& w) { return std::max(0.0, -w.y); };
    EXPECT_GT(lum(latLongIntegral(sky.image(), 1, 0, up, 2)),
              2 * lum(latLongIntegral(sky.image(), 1, 0, down, 2)));
}

// ---------------------------------------------------------------------------
// SphereLight

// 1 / (2 pi (1 - sqrt(1 - (r/d)^2))), in long double.
double analyticConePdf(double r, double d) {
    const long double s = static_cast<long double>(r) / d;
    return static_cast<double>(1.0L / (2.0L * std::acos(-1.0L) * (1.0L - std::sqrt(1.0L - s * s))));
}

TEST(SphereLight, PdfIsOneOverTheSubtendedSolidAngle) {
    const Vec3 c{1, -2, 3};
    for (double r : {0.01, 1.0, 250.0})
        for (double ratio : {1.0001, 1.5, 2.0, 10.0, 1e4}) {
            const SphereLight light(c, r, Rgb(1));
            const Vec3 dir = normalize({0.3, -0.8, 0.5});
            const Vec3 p = c + dir * (r * ratio);
            const double want = analyticConePdf(r, r * ratio);
            EXPECT_NEAR(light.pdf(p, -dir), want, 1e-7 * want) << r << " " << ratio;
            const LightSample s = light.sample(p, {0.3, 0.7});
            ASSERT_TRUE(s.valid());
            EXPECT_NEAR(s.pdf, want, 1e-7 * want);
            // Outside the cone: zero.
            EXPECT_EQ(light.pdf(p, dir), 0);
            const double sinMax = 1 / ratio;
            const Frame f = Frame::fromZ(-dir);
            const double outside = std::asin(sinMax) * 1.01 + 1e-6;
            if (outside < kHalfPi) {
                EXPECT_EQ(light.pdf(p, f.fromLocal({std::sin(outside), 0, std::cos(outside)})), 0);
            }
            const double inside = std::asin(sinMax) * 0.99;
            EXPECT_GT(light.pdf(p, f.fromLocal({0, std::sin(inside), std::cos(inside)})), 0);
        }
}

TEST(SphereLight, SamplesHitTheSphereAtTheirDistance) {
    struct Case {
        Vec3 c;
        double r;
        Vec3 p;
    };
    for (const Case& k :
         {Case{{0, 0, 0}, 1, {0, 0, 3}}, Case{{2, 1, -1}, 0.5, {2.1, 1.2, -1.6}},
          Case{{10, 20, 30}, 0.01, {0, 0, 0}}, Case{{0, 5, 0}, 2, {1, -0.5, 0.2}}}) {
        const SphereLight light(k.c, k.r, Rgb(4, 5, 6));
        EXPECT_FALSE(light.isInfinite());
        Rng rng(12, 12);
        for (int n = 0; n < 5000; ++n) {
            const LightSample s = light.sample(k.p, {rng.uniform(), rng.uniform()});
            ASSERT_TRUE(s.valid());
            EXPECT_NEAR(length(s.wi), 1.0, 1e-12);
            EXPECT_EQ(s.radiance, Rgb(4, 5, 6));
            EXPECT_EQ(s.radiance, light.radiance(s.wi));
            EXPECT_NEAR(s.pdf, light.pdf(k.p, s.wi), 1e-12 * s.pdf);
            const Vec3 hit = k.p + s.wi * s.distance;
            EXPECT_NEAR(length(hit - k.c), k.r, 1e-9 * (k.r + length(k.p - k.c)));
            const double t = light.intersect(k.p, s.wi, kInf);
            // Rays near the cone's edge graze the sphere and may round to a miss.
            if (t < 0) {
                const Vec3 toC = k.c - k.p;
                const double cosEdge = std::sqrt(1 - k.r * k.r / dot(toC, toC));
                EXPECT_NEAR(dot(s.wi, normalize(toC)), cosEdge, 1e-9);
            } else {
                EXPECT_NEAR(t, s.distance, 1e-7 * s.distance);
                // The ray ends at the first hit: tMax below it misses.
                EXPECT_LT(light.intersect(k.p, s.wi, 0.999 * t), 0);
            }
        }
    }
}

TEST(SphereLight, SamplesFollowPdfChiSquare) {
    // Grid bins of 5 degrees about the direction to the centre: the cone
    // edges (30 and 45 degrees) are bin edges.
    for (double thetaMaxDeg : {30.0, 45.0}) {
        const Vec3 c{0.5, 1.0, -2.0};
        const double r = 0.7;
        const Vec3 axis = normalize({-1, 2, 0.5});
        const Vec3 p = c - axis * (r / std::sin(radians(thetaMaxDeg)));
        const SphereLight light(c, r, Rgb(1));
        const Chi2Result res = frameChi2(light, p, axis, 36, 24, scaled(300000), 14);
        EXPECT_GT(res.pValue, kChi2Level)
            << "theta_max " << thetaMaxDeg << ": chi2 " << res.statistic << " dof " << res.dof;
    }
}

TEST(SphereLight, PdfIntegratesToOne) {
    for (double ratio : {1.05, 2.0, 20.0}) {
        const Vec3 c{1, 2, 3};
        const Vec3 axis = normalize({0.3, 0.4, -1});
        const Vec3 p = c - axis * ratio;
        const SphereLight light(c, 1.0, Rgb(1));
        // Quadrature about the axis, fine in theta where the cone's edge lies.
        const double integral = integrateSphere([&](const Vec3& w) { return light.pdf(p, w); },
                                                200000, 4, Frame::fromZ(axis));
        EXPECT_NEAR(integral, 1.0, 1e-3) << "d / r = " << ratio;
    }
}

TEST(SphereLight, LightSamplingEstimatesMatchAnalyticIntegrals) {
    const Vec3 c{0, 1, 0};
    const double r = 0.5, dist = 1.0;  // theta_max = 30 degrees
    const Vec3 axis = normalize({1, 1, 1});
    const Vec3 p = c - axis * dist;
    const Rgb L(1, 2, 3);
    const SphereLight light(c, r, L);
    const double sin2Max = 0.25, solidAngle = kTwoPi * (1 - std::sqrt(0.75));
    // f = 1: L times the solid angle, with zero variance.
    const Estimate one = estimateByLightSampling(
        light, p, [](const Vec3&) { return 1.0; }, 1000, 15);
    expectRgbNear(one.mean, L * solidAngle, 1e-12, "f = 1");
    // Cosine about a normal 40 degrees from the axis (the cone lies in its
    // hemisphere): the integral of w over the cone is pi sin^2(theta_max) axis.
    const Frame f = Frame::fromZ(axis);
    const Vec3 n = f.fromLocal({std::sin(radians(40)), 0, std::cos(radians(40))});
    const Estimate cosine = estimateByLightSampling(
        light, p, [&](const Vec3& w) { return std::max(0.0, dot(n, w)); }, scaled(200000), 16);
    const Rgb want = L * (kPi * sin2Max * std::cos(radians(40)));
    EXPECT_NEAR(lum(cosine.mean), lum(want), 5 * cosine.lumStdErr + 1e-9);
}

TEST(SphereLight, PointsInsideOrOnTheSphereGetNoSamples) {
    const SphereLight light({0, 0, 0}, 1.0, Rgb(1));
    for (const Vec3& p : {Vec3{0, 0, 0}, Vec3{0.5, 0.2, -0.1}, Vec3{1, 0, 0}, Vec3{0, -1, 0}}) {
        const LightSample s = light.sample(p, {0.3, 0.6});
        EXPECT_FALSE(s.valid());
        EXPECT_EQ(s.pdf, 0);
        EXPECT_EQ(light.pdf(p, {1, 0, 0}), 0);
        EXPECT_EQ(light.pdf(p, {-1, 0, 0}), 0);
    }
}

TEST(SphereLight, IntersectFindsTheNearestHitInRange) {
    const SphereLight light({1, 2, 3}, 2.0, Rgb(1));
    const Vec3 c{1, 2, 3};
    // Head-on from outside: d - r.
    EXPECT_NEAR(light.intersect(c + Vec3{0, 0, -10}, {0, 0, 1}, kInf), 8.0, 1e-12);
    // Off-centre by h: d - sqrt(r^2 - h^2).
    EXPECT_NEAR(light.intersect(c + Vec3{1, 0, -10}, {0, 0, 1}, kInf), 10 - std::sqrt(3.0), 1e-12);
    // Missing, pointing away, beyond tMax.
    EXPECT_LT(light.intersect(c + Vec3{2.01, 0, -10}, {0, 0, 1}, kInf), 0);
    EXPECT_LT(light.intersect(c + Vec3{0, 0, -10}, {0, 0, -1}, kInf), 0);
    EXPECT_LT(light.intersect(c + Vec3{0, 0, -10}, {0, 0, 1}, 8.0), 0);
    EXPECT_NEAR(light.intersect(c + Vec3{0, 0, -10}, {0, 0, 1}, 8.0 + 1e-9), 8.0, 1e-12);
    // From inside: the exit point.
    EXPECT_NEAR(light.intersect(c + Vec3{0, 0.5, 0}, {0, 1, 0}, kInf), 1.5, 1e-12);
    EXPECT_NEAR(light.intersect(c + Vec3{0, 0.5, 0}, {0, -1, 0}, kInf), 2.5, 1e-12);
    // From the surface: outwards no hit, inwards the far side.
    EXPECT_LT(light.intersect(c + Vec3{2, 0, 0}, {1, 0, 0}, kInf), 0);
    EXPECT_NEAR(light.intersect(c + Vec3{2, 0, 0}, {-1, 0, 0}, kInf), 4.0, 1e-12);
    // A far-away small sphere keeps its precision.
    const SphereLight far({0, 0, 1e6}, 1e-3, Rgb(1));
    EXPECT_NEAR(far.intersect({0, 0, 0}, {0, 0, 1}, kInf), 1e6 - 1e-3, 1e-9);
}

TEST(SphereLight, RejectsBadParameters) {
    for (double bad : {kNaN, kInf}) {
        expectInputError([&] { SphereLight({0, bad, 0}, 1, Rgb(1)); }, {"sphere light", "center"});
        expectInputError([&] { SphereLight({0, 0, 0}, bad, Rgb(1)); }, {"sphere light", "radius"});
        expectInputError(
            [&] {
                SphereLight({0, 0, 0}, 1, Rgb(1, bad, 1));
            },
            {"sphere light", "radiance"});
    }
    for (double bad : {0.0, -1.0})
        expectInputError([&] { SphereLight({0, 0, 0}, bad, Rgb(1)); }, {"sphere light", "radius"});
    expectInputError(
        [] {
            SphereLight({0, 0, 0}, 1, Rgb(-1, 0, 0));
        },
        {"sphere light", "radiance"});
}

// ---------------------------------------------------------------------------
// Point and directional lights: the inverse-square law and a fixed direction,
// written out here from their definitions (delta_lights.h).

TEST(PointLight, SamplesFollowTheInverseSquareLaw) {
    const PointLight light({1, 2, 3}, Rgb(4, 8, 12));
    EXPECT_TRUE(light.isDelta());
    EXPECT_FALSE(light.isInfinite());
    Rng rng(3, 1);
    for (const Vec3& p : {Vec3(1, 2, 1), Vec3(-2, 0, 7), Vec3(1.5, 2, 3)}) {
        const LightSample s = light.sample(p, {rng.uniform(), rng.uniform()});
        const Vec3 d = Vec3(1, 2, 3) - p;
        const double r2 = d.x * d.x + d.y * d.y + d.z * d.z;
        ASSERT_TRUE(s.valid());
        EXPECT_EQ(s.pdf, 1.0);
        EXPECT_NEAR(s.distance, std::sqrt(r2), 1e-12);
        EXPECT_NEAR(dot(s.wi, d / std::sqrt(r2)), 1.0, 1e-12);
        EXPECT_NEAR(s.radiance.g, 8.0 / r2, 1e-12 * 8.0 / r2);
        EXPECT_NEAR(s.radiance.b / s.radiance.r, 3.0, 1e-12);
        // No ray finds it.
        EXPECT_EQ(light.pdf(p, s.wi), 0.0);
        EXPECT_LT(light.intersect(p, s.wi, kInf), 0.0);
    }
    EXPECT_FALSE(light.sample({1, 2, 3}, {0.5, 0.5}).valid());  // at the light itself
    // Phi = 4 pi I.
    EXPECT_NEAR(light.power(1).g, 4 * kPi * 8, 1e-12);
}

TEST(DirectionalLight, SamplesComeFromTheOppositeOfItsDirection) {
    const DirectionalLight light({2, -4, 4}, Rgb(1, 2, 3));
    EXPECT_TRUE(light.isDelta());
    EXPECT_TRUE(light.isInfinite());
    for (const Vec3& p : {Vec3(0, 0, 0), Vec3(1e3, -5, 2)}) {
        const LightSample s = light.sample(p, {0.25, 0.75});
        ASSERT_TRUE(s.valid());
        EXPECT_EQ(s.pdf, 1.0);
        EXPECT_TRUE(std::isinf(s.distance));
        EXPECT_NEAR(s.wi.x, -1.0 / 3, 1e-15);
        EXPECT_NEAR(s.wi.y, 2.0 / 3, 1e-15);
        EXPECT_NEAR(s.wi.z, -2.0 / 3, 1e-15);
        EXPECT_EQ(s.radiance, Rgb(1, 2, 3));
        EXPECT_EQ(light.pdf(p, s.wi), 0.0);
    }
    // Directions of any magnitude normalize.
    EXPECT_NEAR(DirectionalLight({0, 0, 1e-300}, Rgb(1)).sample({}, {0, 0}).wi.z, -1, 1e-15);
    EXPECT_NEAR(DirectionalLight({1e300, 0, 0}, Rgb(1)).sample({}, {0, 0}).wi.x, -1, 1e-15);
    // Phi = pi R^2 E.
    EXPECT_NEAR(light.power(2).b, kPi * 4 * 3, 1e-12);
}

TEST(DeltaLights, RejectBadParameters) {
    for (double bad : {kNaN, kInf}) {
        expectInputError([&] { PointLight({bad, 0, 0}, Rgb(1)); }, {"point light", "position"});
        expectInputError([&] { PointLight({0, 0, 0}, Rgb(bad)); }, {"point light", "radiance"});
        expectInputError(
            [&] {
                DirectionalLight({0, bad, 1}, Rgb(1));
            },
            {"directional light", "direction"});
        expectInputError(
            [&] {
                DirectionalLight({0, 0, 1}, Rgb(1, 1, bad));
            },
            {"directional light"});
    }
    expectInputError(
        [] {
            DirectionalLight({0, 0, 0}, Rgb(1));
        },
        {"directional light", "direction", "not 0"});
    expectInputError([] { PointLight({0, 0, 0}, Rgb(0, -1, 0)); }, {"point light"});
}

// ---------------------------------------------------------------------------
// Loading an envmap (the image files themselves: core/image_io_test.cpp)

using EnvmapFiles = testing::TempDirTest;

bool sameBits(const Image& a, const Image& b) {
    return a.width == b.width && a.height == b.height && a.pixels.size() == b.pixels.size() &&
           std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) == 0;
}

TEST_F(EnvmapFiles, LoadReadsTheImageFile) {
    // A run-length encoded Radiance file (values with 8-bit mantissas survive RGBE exactly).
    const Image rle = testing::rgbeExactImage();
    const std::string bytes = testing::radianceFileBytes(rle);
    writeFileAtomic(path("rle.HDR"), bytes);
    const EnvironmentLight light = EnvironmentLight::load(path("rle.HDR"), 1.0, 0.0);
    EXPECT_TRUE(sameBits(light.image(), rle));
    // And an OpenEXR file.
    const Image image = randomImage(8, 4, 3);
    writeExr(path("map.exr"), image);
    EXPECT_TRUE(sameBits(EnvironmentLight::load(path("map.exr"), 2.0, 30.0).image(), image));
}

TEST_F(EnvmapFiles, LoadValidatesTheFileAndItsTexels) {
    expectInputError([&] { EnvironmentLight::load(path("missing.exr"), 1, 0); },
                     {path("missing.exr")});
    Image image(4, 2);
    image.set(3, 1, Rgb(1, 1, -2));
    writeExr(path("negative.exr"), image);
    expectInputError([&] { EnvironmentLight::load(path("negative.exr"), 1, 0); },
                     {path("negative.exr"), "texel (x 3, y 1)", "channel B"});
}

}  // namespace
}  // namespace weft::render
