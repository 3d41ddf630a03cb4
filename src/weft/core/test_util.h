// weft/core/test_util.h — helpers shared by the *_test.cpp files (GoogleTest).
#pragma once

#include <gtest/gtest.h>
#include <stb/stb_image_write.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <string>

#include "weft/core/bsdf.h"
#include "weft/core/error.h"
#include "weft/core/image.h"

namespace weft::testing {

// Monte Carlo sample counts in tests are multiplied by this; the sanitizer
// build (WEFT_SANITIZE) runs the same tests with fewer samples.
constexpr double sampleScale() {
#ifdef WEFT_SANITIZED
    return 0.1;
#else
    return 1.0;
#endif
}

constexpr int64_t scaled(int64_t n) {
    const auto s = static_cast<int64_t>(n * sampleScale());
    return s < 1000 ? 1000 : s;
}

// Composite Simpson rule with n (even) intervals: the independent reference
// quadrature of the tests (no tables, no Gauss-Legendre).
template <typename F>
double simpson(const F& f, double a, double b, int n) {
    const double h = (b - a) / n;
    double sum = f(a) + f(b);
    for (int k = 1; k < n; ++k) sum += (k % 2 ? 4.0 : 2.0) * f(a + k * h);
    return sum * h / 3.0;
}

// Runs f and expects an InputError whose message contains every string in parts.
inline void expectInputError(const std::function<void()>& f,
                             std::initializer_list<std::string> parts) {
    try {
        f();
        ADD_FAILURE() << "expected an InputError";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        for (const std::string& p : parts)
            EXPECT_NE(msg.find(p), std::string::npos)
                << "message '" << msg << "' lacks '" << p << "'";
    }
}

// A width x height image of one colour.
inline Image constantImage(int width, int height, const Rgb& colour) {
    Image image(width, height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) image.set(x, y, colour);
    return image;
}

// The bytes of a Radiance .hdr file of `image`, run-length encoded by
// stb_image_write (values with 8-bit mantissas survive RGBE exactly).
inline std::string radianceFileBytes(const Image& image) {
    std::string bytes;
    const int ok = stbi_write_hdr_to_func(
        [](void* ctx, void* data, int size) {
            static_cast<std::string*>(ctx)->append(static_cast<const char*>(data), size);
        },
        &bytes, image.width, image.height, 3, image.pixels.data());
    EXPECT_TRUE(ok) << "stbi_write_hdr_to_func failed";
    return bytes;
}

// A 20 x 3 image whose values have 8-bit mantissas, so that a Radiance file
// (RGBE) keeps them exactly; wide enough for stb_image_write to run-length
// encode its rows.
inline Image rgbeExactImage() {
    Image image(20, 3);
    for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 20; ++x)
            image.set(x, y, Rgb(x < 10 ? 1.0 : 0.5, std::ldexp(x + 1, y - 4), 3.0 * (x % 4 == 0)));
    return image;
}

// The forms of the Bsdf contract (core/bsdf.h) agree at one wo and one sample
// input, bit for bit: evalPdf is (eval, pdf), the slice (prepared for its wi)
// gives the (wi, wo) results, and the slice's sample equals sample(wi, u, rng)
// for the same generator stream. Returns that sample (for the caller's own
// checks of weight = eval / pdf).
inline BsdfSample expectBsdfFormsAgree(const Bsdf& bsdf, const BsdfSlice& slice, const Vec3& wo,
                                       const BsdfSampleInput& u, uint64_t stream) {
    const Vec3& wi = slice.wi();
    const BsdfEval e = bsdf.evalPdf(wi, wo);
    EXPECT_EQ(e.value, bsdf.eval(wi, wo));
    EXPECT_EQ(e.pdf, bsdf.pdf(wi, wo));
    EXPECT_EQ(slice.evalPdf(wo).value, e.value);
    EXPECT_EQ(slice.evalPdf(wo).pdf, e.pdf);
    EXPECT_EQ(slice.eval(wo), e.value);
    EXPECT_EQ(slice.pdf(wo), e.pdf);
    Rng a(stream, 1), b(stream, 1);
    const BsdfSample s = slice.sample(u, a), t = bsdf.sample(wi, u, b);
    EXPECT_EQ(s.wo, t.wo);
    EXPECT_EQ(s.weight, t.weight);
    EXPECT_EQ(s.pdf, t.pdf);
    EXPECT_EQ(s.lobe, t.lobe);
    return s;
}

// The mean of sample()'s weight over n samples at wi (invalid samples count
// as 0) and its standard error, per channel: E[eval / pdf] is the directional
// albedo, the independent truth a quadrature of eval gives.
struct WeightMean {
    Rgb mean, standardError;
};
inline WeightMean meanSampleWeight(const Bsdf& bsdf, const Vec3& wi, int64_t n, Rng& rng) {
    Rgb sum, sumSq;
    for (int64_t k = 0; k < n; ++k) {
        const BsdfSample s = bsdf.sample(wi, {rng.uniform(), rng.uniform(), rng.uniform()}, rng);
        if (!s.valid()) continue;
        sum += s.weight;
        sumSq += s.weight * s.weight;
    }
    WeightMean m;
    const double count = static_cast<double>(n);
    for (int c = 0; c < 3; ++c) {
        m.mean[c] = sum[c] / count;
        m.standardError[c] =
            std::sqrt(std::max(0.0, sumSq[c] / count - m.mean[c] * m.mean[c]) / count);
    }
    return m;
}

// A fixture with a fresh directory per test, removed afterwards.
class TempDirTest : public ::testing::Test {
  protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = std::filesystem::path(::testing::TempDir()) /
               (std::string("weft_") + info->test_suite_name() + "." + std::to_string(::getpid()) +
                "." + info->name());
        std::filesystem::remove_all(dir_);
        std::filesystem::create_directories(dir_);
    }
    void TearDown() override {
        std::error_code ignored;
        std::filesystem::permissions(dir_, std::filesystem::perms::owner_all,
                                     std::filesystem::perm_options::add, ignored);
        std::filesystem::remove_all(dir_);
    }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }

    std::filesystem::path dir_;
};

}  // namespace weft::testing
