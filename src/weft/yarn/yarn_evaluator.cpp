#include "weft/yarn/yarn_evaluator.h"

#include <algorithm>
#include <cmath>

#include "weft/core/error.h"

namespace weft {

namespace {

// The model's own checks (yarn_model.h), before any member is built.
const YarnModel& validated(const YarnModel& model, const std::string& source) {
    try {
        model.validate();
        // The file format holds any float; inference must stay finite.
        model.tNet.checkFiniteOnUnitInputs("t_net");
        model.mNet.checkFiniteOnUnitInputs("m_net");
    } catch (const InputError& e) {
        throw InputError(source + ": " + e.what());
    }
    return model;
}

// Builds a member, prefixing the InputError of its constructor with `source`.
template <typename T, typename... Args>
T withSource(const std::string& source, const Args&... args) {
    try {
        return T(args...);
    } catch (const InputError& e) {
        throw InputError(source + ": " + e.what());
    }
}

}  // namespace

YarnEvaluator::YarnEvaluator(const YarnModel& model, const std::string& source, bool energyGuard)
    : tNet_(validated(model, source).tNet, source + ": t_net"),
      mNet_(model.mNet, source + ": m_net"),
      rLobe_(withSource<RLobe>(source, model.fiber, model.rLobe)),
      ablation_(model.ablation),
      hasTransmission_(model.hasTransmissionLobe()),
      hasReflection_(model.hasReflectionLobe()),
      calibration_(model.calibration) {
    if (energyGuard) guard_ = EnergyGuard(*this);
}

size_t YarnEvaluator::memoryBytes() const {
    return sizeof(*this) + rLobe_.fiber().memoryBytes() - sizeof(FiberBcsdf) +
           guard_.memoryBytes();
}

double YarnEvaluator::transmission(const Vec3& wi) const {
    return hasTransmission_ ? evalTransmission(tNet_, wi) : 0.0;
}

Rgb YarnEvaluator::evalM(const Vec3& wi, const Vec3& wo) const {
    return evalScattering(mNet_, wi, wo);
}

void YarnEvaluator::evalMBatch(const Vec3& wi, const Vec3* wo, size_t count, Rgb* out) const {
    evalScatteringBatch(mNet_, &wi, 0, wo, count, out);
}

void YarnEvaluator::evalMBatch(const Vec3* wi, const Vec3* wo, size_t count, Rgb* out) const {
    evalScatteringBatch(mNet_, wi, 1, wo, count, out);
}

void YarnEvaluator::transmissionBatch(const Vec3* wi, size_t count, double* out) const {
    if (hasTransmission_)
        evalTransmissionBatch(tNet_, wi, count, out);
    else
        std::fill(out, out + count, 0.0);
}

SurfaceFiberAngles YarnEvaluator::surfaceAngles(const Vec3& wi) const {
    SurfaceFiberAngles s;
    s.local = frame().toLocal(wi);
    s.angles = FiberBcsdf::anglesOf(s.local);
    s.phi = std::atan2(s.local.y, std::max(s.local.z, 0.0));
    return s;
}

FiberBcsdf::Angles YarnEvaluator::outAngles(const Vec3& wo) const {
    if (!hasReflection_ || wo.z <= 0) return {};
    return FiberBcsdf::anglesOf(frame().toLocal(wo));
}

void YarnEvaluator::prepare(const SurfaceFiberAngles& surface, YarnIncident& in) const {
    const EnergyCalibration::Scales s = calibration_.scales(in.wi);
    const EnergyGuard::Scales g = guard_.scales(in.wi, surface, in.pT, s, rLobe_.fiber());
    in.rScale = s.r * g.r;
    in.mScale = s.m * g.m;
    if (hasReflection_) in.fiber = rLobe_.fiber().incident(surface.angles);
}

YarnIncident YarnEvaluator::incident(const Vec3& wi) const {
    YarnIncident in;
    in.wi = wi;
    in.pT = transmission(wi);
    prepare(surfaceAngles(wi), in);
    return in;
}

YarnComponents YarnEvaluator::components(const Vec3& wo, const YarnIncident& in,
                                         const FiberBcsdf::Angles& out) const {
    return components(in, wo, out, evalM(in.wi, wo));
}

YarnComponents YarnEvaluator::components(const YarnIncident& in, const Vec3& wo,
                                         const FiberBcsdf::Angles& out, const Rgb& m) const {
    YarnComponents c;
    c.pT = in.pT;
    if (hasReflection_) c.r = rLobe_.eval(in.wi, wo, in.fiber, out, in.pT) * in.rScale;
    c.m = m * in.mScale;
    return c;
}

void YarnEvaluator::componentsBatch(const Vec3* wo, size_t count, const YarnIncident& in,
                                    YarnComponents* out) const {
    constexpr size_t kChunk = 64;
    Rgb m[kChunk];
    for (size_t first = 0; first < count; first += kChunk) {
        const size_t n = std::min(kChunk, count - first);
        evalMBatch(in.wi, wo + first, n, m);
        for (size_t k = 0; k < n; ++k)
            out[first + k] = components(in, wo[first + k], outAngles(wo[first + k]), m[k]);
    }
}

Rgb YarnEvaluator::multipleScatteringScale(const Vec3& wi) const {
    const Vec3 i = wi.z < 0 ? mirrored(wi) : wi;
    return guard_.scales(i, surfaceAngles(i), transmission(i), calibration_.scales(i),
                         rLobe_.fiber())
        .m;
}

}  // namespace weft
