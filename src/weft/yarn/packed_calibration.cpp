// weft/yarn/packed_calibration.cpp — PackedCalibration's kernel, one per
// instruction set (Google Highway, dynamic dispatch; see fixed_mlp.cpp for
// how foreach_target compiles this file once per target).
#include "weft/yarn/packed_calibration.h"

#include <stdexcept>

#ifndef HWY_DISABLED_TARGETS
#define HWY_DISABLED_TARGETS (HWY_SVE | HWY_SVE2 | HWY_SVE_256 | HWY_SVE2_128 | HWY_RVV)
#endif

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "weft/yarn/packed_calibration.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h

#include <hwy/contrib/math/math-inl.h>
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace weft {
namespace HWY_NAMESPACE {
namespace {

namespace hn = hwy::HWY_NAMESPACE;

constexpr int kLanes = PackedCalibrationKernel::kLanes;
using Tag = hn::CappedTag<double, kLanes>;
using Vector = hn::Vec<Tag>;

// One vector of lanes [first, first + Lanes): eight partial sums over k mod 8
// (independent chains of multiply-adds; one would be a chain of `terms`
// dependent ones), added pairwise, clamped, exponentiated.
HWY_INLINE void lanesOf(const double* HWY_RESTRICT c, const double* HWY_RESTRICT f, int terms,
                        int first, double* HWY_RESTRICT out) {
    const Tag d;
    constexpr int kSums = 8;
    Vector s[kSums];
    for (int j = 0; j < kSums; ++j) s[j] = hn::Zero(d);
    const double* p = c + first;
    int k = 0;
    for (; k + kSums <= terms; k += kSums, p += kSums * kLanes)
        for (int j = 0; j < kSums; ++j)
            s[j] = hn::MulAdd(hn::LoadU(d, p + j * kLanes), hn::Set(d, f[k + j]), s[j]);
    for (int j = 0; k < terms; ++k, ++j, p += kLanes)
        s[j] = hn::MulAdd(hn::LoadU(d, p), hn::Set(d, f[k]), s[j]);
    for (int width = kSums / 2; width > 0; width /= 2)
        for (int j = 0; j < width; ++j) s[j] = hn::Add(s[j], s[j + width]);
    const Vector bound = hn::Set(d, EnergyCalibration::kMaxLogScale);
    const Vector logScale = hn::Min(hn::Max(s[0], hn::Neg(bound)), bound);
    hn::StoreU(hn::Exp(d, logScale), d, out + first);
}

void scales(const double* HWY_RESTRICT coefficients, const double* HWY_RESTRICT basis, int terms,
            double* HWY_RESTRICT out) {
    const int lanes = static_cast<int>(hn::Lanes(Tag()));
    for (int first = 0; first < kLanes; first += lanes)
        lanesOf(coefficients, basis, terms, first, out);
}

}  // namespace

PackedCalibrationKernel selectPackedCalibrationKernel() {
    PackedCalibrationKernel kernel;
    kernel.scales = &scales;
    kernel.target = hwy::TargetName(HWY_TARGET);
    return kernel;
}

}  // namespace HWY_NAMESPACE
}  // namespace weft
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include "weft/yarn/highway_targets.h"

namespace weft {

HWY_EXPORT(selectPackedCalibrationKernel);

std::vector<PackedCalibrationKernel> packedCalibrationKernels() {
    return everyHighwayTarget([] { return HWY_DYNAMIC_DISPATCH(selectPackedCalibrationKernel)(); });
}

PackedCalibration::PackedCalibration(const EnergyCalibration& calibration)
    : PackedCalibration(calibration, HWY_DYNAMIC_DISPATCH(selectPackedCalibrationKernel)()) {}

PackedCalibration::PackedCalibration(const EnergyCalibration& calibration,
                                     const PackedCalibrationKernel& kernel)
    : degree_(calibration.degree), kernel_(kernel) {
    if (empty()) return;
    // The model's reader validated the calibration (yarn_model.h); the stack
    // basis of scales() holds kMaxDegree's terms.
    terms_ = EnergyCalibration::termCount(degree_);
    for (int c = 0; c < 3; ++c)
        if (degree_ > EnergyCalibration::kMaxDegree ||
            calibration.r[c].size() != static_cast<size_t>(terms_) ||
            calibration.m[c].size() != static_cast<size_t>(terms_))
            throw std::logic_error("PackedCalibration: an unvalidated energy calibration");
    constexpr size_t kLanes = PackedCalibrationKernel::kLanes;
    coefficients_.assign(terms_ * kLanes, 0.0);
    for (int k = 0; k < terms_; ++k)
        for (int c = 0; c < 3; ++c) {
            coefficients_[k * kLanes + c] = calibration.r[c][k];
            coefficients_[k * kLanes + 3 + c] = calibration.m[c][k];
        }
}

EnergyCalibration::Scales PackedCalibration::scales(const Vec3& wi) const {
    EnergyCalibration::Scales s;
    if (empty()) return s;
    double f[EnergyCalibration::termCount(EnergyCalibration::kMaxDegree)];
    EnergyCalibration::basis(wi, degree_, f);
    alignas(64) double out[PackedCalibrationKernel::kLanes];
    kernel_.scales(coefficients_.data(), f, terms_, out);
    s.r = Rgb(out[0], out[1], out[2]);
    s.m = Rgb(out[3], out[4], out[5]);
    return s;
}

}  // namespace weft
#endif  // HWY_ONCE
