#include "weft/yarn/yarn_bsdf.h"

#include "weft/yarn/yarn_lobes.h"

namespace weft {

namespace {

// wo in the incident's upper-hemisphere convention.
Vec3 upperSide(const YarnIncident& in, const Vec3& wo) { return in.mirrored ? mirrored(wo) : wo; }

}  // namespace

YarnBsdf::YarnBsdf(const YarnModel& model, const std::string& source,
                   const YarnBsdfOptions& options)
    : YarnBsdf(model.colour ? model.forColour(model.ownColourInRange(), source) : model, source,
               options, OneColour{}) {}

YarnBsdf::YarnBsdf(const YarnModel& model, const std::string& source,
                   const YarnBsdfOptions& options, OneColour)
    // `new`, not make_shared: the evaluator's networks are over-aligned (FixedMlp).
    : model_(new YarnEvaluator(model, source, options.energyGuard)),
      sampler_(makeYarnSampler(options.sampling, model, model_)) {}

YarnBsdf YarnBsdf::load(const std::string& path, const YarnBsdfOptions& options) {
    return YarnBsdf(loadYarnModel(path), path, options);
}

size_t YarnBsdf::memoryBytes() const {
    return sizeof(*this) + model_->memoryBytes() + sampler_->memoryBytes();
}

double YarnBsdf::transmission(const Vec3& wi) const {
    return model_->transmission(wi.z < 0 ? mirrored(wi) : wi);
}

YarnIncident YarnBsdf::incident(const Vec3& wi) const {
    YarnIncident in;
    in.mirrored = wi.z < 0;
    in.wi = in.mirrored ? mirrored(wi) : wi;
    in.pT = model_->transmission(in.wi);
    const SurfaceFiberAngles surface = model_->surfaceAngles(in.wi);
    model_->prepare(surface, in);
    sampler_->prepare(surface, in);
    return in;
}

void YarnBsdf::evalAndPdf(const YarnIncident& in, const Vec3& wo, Rgb* value,
                          double* density) const {
    const FiberBcsdf::Angles out = value || sampler_->pdfNeedsOutAngles() ? model_->outAngles(wo)
                                                                         : FiberBcsdf::Angles{};
    if (value) {
        const YarnComponents parts = model_->components(wo, in, out);
        *value = parts.m;
        if (model_->hasReflection()) *value += parts.r;
    }
    if (density) *density = sampler_->pdf(in, wo, out);
}

void YarnBsdf::prepare(const Vec3& wi, BsdfIncident& in) const { in.emplace(wi, incident(wi)); }

BsdfEval YarnBsdf::evalPdf(const BsdfIncident& in, const Vec3& wo) const {
    const YarnIncident& yarn = in.get<YarnIncident>();
    BsdfEval e;
    evalAndPdf(yarn, upperSide(yarn, wo), &e.value, &e.pdf);
    return e;
}

Rgb YarnBsdf::eval(const BsdfIncident& in, const Vec3& wo) const {
    const YarnIncident& yarn = in.get<YarnIncident>();
    Rgb value;
    evalAndPdf(yarn, upperSide(yarn, wo), &value, nullptr);
    return value;
}

double YarnBsdf::pdf(const BsdfIncident& in, const Vec3& wo) const {
    const YarnIncident& yarn = in.get<YarnIncident>();
    double density;
    evalAndPdf(yarn, upperSide(yarn, wo), nullptr, &density);
    return density;
}

double YarnBsdf::pdf(const Vec3& wi, const Vec3& wo) const {
    if (sampler_->usesModelScales()) return Bsdf::pdf(wi, wo);
    // The sampler needs P(T) alone: no calibration, no energy guard.
    YarnIncident in;
    in.mirrored = wi.z < 0;
    in.wi = in.mirrored ? mirrored(wi) : wi;
    in.pT = model_->transmission(in.wi);
    in.rScale = in.mScale = Rgb(1.0);
    sampler_->prepare(SurfaceFiberAngles{}, in);
    double density;
    evalAndPdf(in, upperSide(in, wo), nullptr, &density);
    return density;
}

YarnComponents YarnBsdf::components(const Vec3& wi, const Vec3& wo) const {
    const bool flip = wi.z < 0;
    return model_->components(flip ? mirrored(wo) : wo, model_->incident(flip ? mirrored(wi) : wi));
}

YarnLobeProbabilities YarnBsdf::lobeProbabilities(const Vec3& wi) const {
    return sampler_->lobeProbabilities(incident(wi));
}

BsdfSample YarnBsdf::sample(const BsdfIncident& in, const BsdfSampleInput& u, Rng& rng) const {
    const YarnIncident& yarn = in.get<YarnIncident>();
    if (u[0] < yarn.pickT) {
        // S_T = P(T|wi) delta(wo + wi), chosen with probability P_T.
        BsdfSample s;
        s.wo = -in.wi();
        s.weight = Rgb(yarn.pT / yarn.pickT);
        s.pdf = 0;
        s.lobe = kLobeT;
        s.isDelta = true;
        return s;
    }
    const YarnDirectionSample d = sampler_->sample(yarn, u, rng);
    BsdfEval e;
    evalAndPdf(yarn, d.wo, &e.value, &e.pdf);
    return BsdfSample::fromEval(yarn.mirrored ? mirrored(d.wo) : d.wo, e, d.lobe);
}

}  // namespace weft
