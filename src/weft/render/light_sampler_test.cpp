// Tests of the light samplers (issue 45): pick probabilities sum to 1 and
// match the weights, the picks follow them (chi-square), the uniform pick is
// the one weft made before samplers, lights' power is pbrt's Phi, and the
// scene file's "light_sampler" is read strictly.
#include "weft/render/light_sampler.h"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <vector>

#include "weft/core/math.h"
#include "weft/core/rng.h"
#include "weft/core/test_util.h"
#include "weft/render/constant_light.h"
#include "weft/render/environment_light.h"
#include "weft/render/scene.h"
#include "weft/render/scene_file.h"
#include "weft/render/sphere_light.h"

namespace weft::render {
namespace {

using weft::testing::expectInputError;

TEST(LightSampler, PicksFollowTheirProbabilities) {
    const std::vector<double> weights = {3, 0, 1, 0.5, 5.5};
    const LightSampler sampler(weights);
    double sum = 0;
    for (size_t i = 0; i < weights.size(); ++i) {
        EXPECT_DOUBLE_EQ(sampler.pmf(i), weights[i] / 10.0);
        sum += sampler.pmf(i);
    }
    EXPECT_NEAR(sum, 1.0, 1e-15);
    // Chi-square of 200,000 picks against the pmf (4 degrees of freedom: the
    // zero-weight light is never picked; 99.99th percentile 23.5).
    const int n = 200000;
    std::vector<int> counts(weights.size(), 0);
    Rng rng(7, 1);
    for (int k = 0; k < n; ++k) {
        double pmf = 0;
        const int i = sampler.sample(rng.uniform(), &pmf);
        ASSERT_EQ(pmf, sampler.pmf(i));
        ++counts[i];
    }
    EXPECT_EQ(counts[1], 0);
    double chi2 = 0;
    for (size_t i = 0; i < weights.size(); ++i) {
        if (weights[i] == 0) continue;
        const double expected = n * sampler.pmf(i);
        chi2 += (counts[i] - expected) * (counts[i] - expected) / expected;
    }
    EXPECT_LT(chi2, 23.5);
    // The ends of [0, 1) land on lights that can be picked.
    double pmf = 0;
    EXPECT_EQ(sampler.sample(0.0, &pmf), 0);
    EXPECT_EQ(sampler.sample(std::nextafter(1.0, 0.0), &pmf), 4);
}

TEST(LightSampler, UniformIsThePickOfBeforeAndZeroWeightsFallBackToIt) {
    const LightSampler uniform(size_t{3});
    for (double u : {0.0, 0.2, 0.34, 0.5, 0.67, 0.99, std::nextafter(1.0, 0.0)}) {
        double pmf = 0;
        EXPECT_EQ(uniform.sample(u, &pmf), std::min(static_cast<int>(u * 3), 2));
        EXPECT_DOUBLE_EQ(pmf, 1.0 / 3);
    }
    const LightSampler dark(std::vector<double>{0, 0});
    EXPECT_DOUBLE_EQ(dark.pmf(0), 0.5);
    EXPECT_THROW(LightSampler(std::vector<double>{1, NAN}), InputError);
}

TEST(LightSampler, PowerIsPbrtsPhi) {
    // A sphere: pi A L; a constant sky: 4 pi^2 R^2 L; an environment map of
    // one colour: the same as that constant sky (the quadrature of radiance).
    EXPECT_NEAR(SphereLight(Vec3(0, 0, 0), 0.5, Rgb(2.0)).power(10).g, kPi * kPi * 2.0, 1e-12);
    EXPECT_NEAR(ConstantLight(Rgb(0.25)).power(3).r, 4 * kPi * kPi * 9 * 0.25, 1e-12);
    Image flat(16, 8);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 16; ++x) flat.set(x, y, Rgb(0.25));
    const EnvironmentLight env(flat, 1.0, 0.0, "flat");
    EXPECT_NEAR(env.power(3).b, 4 * kPi * kPi * 9 * 0.25, 1e-9);
    // The procedural sky: its average radiance, independently by Monte Carlo.
    const EnvironmentLight sky = skyLight();
    Rng rng(3, 2);
    double mc = 0;
    const int n = 200000;
    for (int k = 0; k < n; ++k) {
        const double z = 1 - 2 * rng.uniform(), phi = kTwoPi * rng.uniform();
        const double s = std::sqrt(1 - z * z);
        mc += sky.radiance(Vec3(s * std::cos(phi), s * std::sin(phi), z)).average();
    }
    mc /= n;
    EXPECT_NEAR(averageRadiance(sky).average(), mc, 0.01 * mc);
}

TEST(LightSampler, SceneFilesNameItAndItRoundTrips) {
    auto parse = [](const std::string& sampler, int lights = 2) {
        std::string text = R"({"camera": {"from": [0, 0, 1], "to": [0, 0, 0]}, "lights": [)";
        for (int i = 0; i < lights; ++i)
            text += std::string(i ? ", " : "") + R"({"type": "constant", "radiance": [1, 1, 1]})";
        text += "]" + (sampler.empty() ? std::string() : ", \"light_sampler\": " + sampler) + "}";
        return parseSceneText(text, "scene.json", "/nonexistent");
    };
    EXPECT_EQ(parse("").lightSampler.kind, LightSamplerKind::Uniform);
    EXPECT_EQ(parse("\"power\"").lightSampler.kind, LightSamplerKind::Power);
    const SceneDesc weighted = parse(R"({"weights": [2, 0.5]})");
    EXPECT_EQ(weighted.lightSampler.weights, (std::vector<double>{2, 0.5}));
    const SceneDesc again = parseScene(toJson(weighted), "again", "/nonexistent");
    EXPECT_EQ(again.lightSampler.weights, weighted.lightSampler.weights);
    // Uniform is not written: a scene without a sampler keeps its hash.
    EXPECT_FALSE(toJson(parse("")).contains("light_sampler"));
    expectInputError([&] { parse("\"bvh\""); },
                     {"scene.json", "light_sampler", "uniform", "power"});
    expectInputError([&] { parse("3"); }, {"light_sampler", "weights"});
    expectInputError([&] { parse(R"({"weights": [1]})"); }, {"light_sampler.weights", "2 numbers"});
    expectInputError([&] { parse(R"({"weights": [1, -1]})"); }, {"light_sampler.weights", ">= 0"});
    expectInputError([&] { parse(R"({"weights": [0, 0]})"); }, {"at least one weight"});
    expectInputError([&] { parse(R"({"weights": [1, 1], "x": 1})"); }, {"unknown key \"x\""});
    // No lights: the procedural sky is the one light.
    EXPECT_EQ(parse(R"({"weights": [1]})", 0).lightSampler.weights.size(), 1u);
}

// A point or directional light is reached only by light samples: a weight of
// 0 would drop it from the image, so the scene refuses it.
TEST(LightSampler, DeltaLightsNeedAWeight) {
    const auto scene = [](const std::string& weights) {
        return parseSceneText(R"({"camera": {"from": [0, 0, 1], "to": [0, 0, 0]}, "lights": [
            {"type": "constant", "radiance": [1, 1, 1]},
            {"type": "point", "position": [0, 1, 0], "intensity": [1, 1, 1]}],
            "light_sampler": {"weights": )" +
                                  weights + "}}",
                              "scene.json", "/nonexistent");
    };
    expectInputError([&] { Scene s(scene("[1, 0]")); },
                     {"light_sampler.weights[1] = 0", "lights[1]", "point or directional"});
    const Scene ok(scene("[1, 3]"));
    EXPECT_NEAR(ok.lightSampler().pmf(1), 0.75, 1e-15);
    EXPECT_TRUE(ok.lights()[1]->isDelta());
}

}  // namespace
}  // namespace weft::render
