#include "weft/core/bsdf.h"

#include <gtest/gtest.h>

#include <cmath>

#include "weft/core/math.h"
#include "weft/core/test_util.h"

namespace weft {
namespace {

// A toy BSDF for the contract alone: Lambertian about +z, sampled by the
// cosine, with an albedo that depends on wi (so the incident state matters),
// black below the surface. Counts prepare() calls.
class ToyBsdf final : public Bsdf {
  public:
    using Bsdf::eval;
    using Bsdf::evalPdf;
    using Bsdf::pdf;
    using Bsdf::sample;

    void prepare(const Vec3& wi, BsdfIncident& in) const override {
        ++prepares;
        in.emplace(wi, State{Rgb(0.2, 0.5, 0.8) * (0.5 + 0.5 * std::fabs(wi.z))});
    }
    BsdfEval evalPdf(const BsdfIncident& in, const Vec3& wo) const override {
        if (wo.z <= 0) return {};
        return {in.get<State>().albedo * (wo.z * kInvPi), wo.z * kInvPi};
    }
    BsdfSample sample(const BsdfIncident& in, const BsdfSampleInput& u, Rng& rng) const override {
        // One extra draw from rng, as a rejection step would.
        const double phi = kTwoPi * (u[2] + 0.25 * rng.uniform());
        const double r = std::sqrt(u[1]);
        const Vec3 wo{r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0, 1 - u[1]))};
        return BsdfSample::fromEval(wo, evalPdf(in, wo), 0);
    }

    size_t memoryBytes() const override { return sizeof(*this); }

    mutable int prepares = 0;

  private:
    struct State {
        Rgb albedo;
    };
};

Vec3 direction(double thetaDeg, double phiDeg) {
    const double t = radians(thetaDeg), p = radians(phiDeg);
    return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

TEST(BsdfIncident, HoldsWiAndTheStateAsWritten) {
    struct State {
        double a[15];
        int k;
    };
    static_assert(sizeof(State) <= BsdfIncident::kStateBytes);
    State s{};
    for (int i = 0; i < 15; ++i) s.a[i] = i * 0.5;
    s.k = 7;
    BsdfIncident in;
    in.emplace(Vec3{1, 2, 3}, s);
    const BsdfIncident copy = in;  // trivially copyable: a slice copies it
    EXPECT_EQ(copy.wi(), (Vec3{1, 2, 3}));
    EXPECT_EQ(copy.get<State>().a[14], 7.0);
    EXPECT_EQ(copy.get<State>().k, 7);
    static_assert(std::is_trivially_copyable_v<BsdfIncident>);
}

TEST(BsdfSample, FromEvalDividesOnceAndRejectsZeroPdf) {
    const BsdfSample s = BsdfSample::fromEval({0, 0, 1}, {Rgb(0.5, 1, 2), 0.25}, 3);
    EXPECT_TRUE(s.valid());
    EXPECT_EQ(s.weight, Rgb(0.5, 1, 2) / 0.25);
    EXPECT_EQ(s.pdf, 0.25);
    EXPECT_EQ(s.lobe, 3);
    EXPECT_FALSE(s.isDelta);
    for (double pdf : {0.0, -1.0, std::nan("")}) {
        const BsdfSample bad = BsdfSample::fromEval({0, 0, 1}, {Rgb(1), pdf}, 0);
        EXPECT_FALSE(bad.valid());
        EXPECT_TRUE(bad.weight.isBlack());
        EXPECT_EQ(bad.pdf, 0.0);
    }
}

TEST(Bsdf, AllFormsAgreeAndASlicePreparesOnce) {
    const ToyBsdf toy;
    const Bsdf& bsdf = toy;
    Rng rng(3, 3);
    for (const Vec3& wi : {direction(10, 20), direction(70, -100), direction(120, 45)}) {
        toy.prepares = 0;
        const BsdfSlice slice = bsdf.slice(wi);
        EXPECT_EQ(slice.wi(), wi);
        for (int k = 0; k < 20; ++k) {
            const Vec3 wo = direction(180 * rng.uniform(), 360 * rng.uniform());
            const BsdfSampleInput u = {rng.uniform(), rng.uniform(), rng.uniform()};
            const BsdfSample s = testing::expectBsdfFormsAgree(bsdf, slice, wo, u, k);
            EXPECT_EQ(bsdf.sample(wi, u).wo, slice.sample(u).wo);
            // weight = eval / pdf at the sampled direction.
            const BsdfEval at = bsdf.evalPdf(wi, s.wo);
            EXPECT_EQ(s.weight, at.value / at.pdf);
            EXPECT_EQ(s.pdf, at.pdf);
        }
        EXPECT_EQ(toy.prepares, 1 + 20 * 6);  // the slice once, each (wi, ...) call once
    }
}

TEST(Bsdf, SampleWithoutAGeneratorSeedsItFromU) {
    const ToyBsdf toy;
    const Vec3 wi = direction(30, 60);
    const BsdfSampleInput u = {0.3, 0.6, 0.9};
    Rng rng = bsdfSampleRng(u);
    const BsdfSample a = toy.sample(wi, u), b = toy.sample(wi, u, rng);
    EXPECT_EQ(a.wo, b.wo);
    EXPECT_EQ(a.weight, b.weight);
}

}  // namespace
}  // namespace weft
