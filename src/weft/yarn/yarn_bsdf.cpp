#include "weft/yarn/yarn_bsdf.h"

#include <algorithm>

#include "weft/yarn/tabulated_sampler.h"
#include "weft/yarn/yarn_lobes.h"

namespace weft {

namespace {

// wo in the incident's upper-hemisphere convention.
Vec3 upperSide(const YarnIncident& in, const Vec3& wo) { return in.mirrored ? mirrored(wo) : wo; }

// S_T = P(T|wi) delta(wo + wi), chosen with probability P_T.
BsdfSample transmissionSample(const BsdfIncident& in) {
    const YarnIncident& yarn = in.get<YarnIncident>();
    BsdfSample s;
    s.wo = -in.wi();
    s.weight = Rgb(yarn.pT / yarn.pickT);
    s.pdf = 0;
    s.lobe = YarnBsdf::kLobeT;
    s.isDelta = true;
    return s;
}

// The batches gather the networks' inputs in chunks of this many on the stack.
constexpr size_t kBatchChunk = 64;

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

std::unique_ptr<YarnBsdf> YarnBsdf::withTabulatedSampling() const {
    auto bsdf = std::make_unique<YarnBsdf>(*this);
    bsdf->sampler_ = std::make_shared<TabulatedYarnSampler>(model_);
    return bsdf;
}

YarnBsdf YarnBsdf::load(const std::string& path, const YarnBsdfOptions& options) {
    return YarnBsdf(loadYarnModel(path), path, options);
}

size_t YarnBsdf::memoryBytes() const {
    return sizeof(*this) + model_->memoryBytes() + sampler_->memoryBytes();
}

double YarnBsdf::transmission(const Vec3& wi) const {
    return model_->transmission(wi.z < 0 ? mirrored(wi) : wi);
}

YarnIncident YarnBsdf::incident(const Vec3& wi) const { return incident(wi, transmission(wi)); }

YarnIncident YarnBsdf::incident(const Vec3& wi, double pT) const {
    YarnIncident in;
    in.mirrored = wi.z < 0;
    in.wi = in.mirrored ? mirrored(wi) : wi;
    in.pT = pT;
    const SurfaceFiberAngles surface = model_->surfaceAngles(in.wi);
    model_->prepare(surface, in);
    sampler_->prepare(surface, in);
    return in;
}

void YarnBsdf::evalAndPdf(const YarnIncident& in, const Vec3& wo, Rgb* value, double* density,
                          const Rgb* m) const {
    const FiberBcsdf::Angles out = value || sampler_->pdfNeedsOutAngles() ? model_->outAngles(wo)
                                                                         : FiberBcsdf::Angles{};
    if (value) {
        const YarnComponents parts =
            m ? model_->components(in, wo, out, *m) : model_->components(wo, in, out);
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
    if (u[0] < yarn.pickT) return transmissionSample(in);
    const YarnDirectionSample d = sampler_->sample(yarn, u, rng);
    BsdfEval e;
    evalAndPdf(yarn, d.wo, &e.value, &e.pdf);
    return BsdfSample::fromEval(yarn.mirrored ? mirrored(d.wo) : d.wo, e, d.lobe);
}

void YarnBsdf::prepareBatch(const Vec3* wi, BsdfIncident* const* in, size_t count) const {
    Vec3 upper[kBatchChunk];
    double pT[kBatchChunk];
    for (size_t first = 0; first < count; first += kBatchChunk) {
        const size_t n = std::min(kBatchChunk, count - first);
        for (size_t k = 0; k < n; ++k)
            upper[k] = wi[first + k].z < 0 ? mirrored(wi[first + k]) : wi[first + k];
        model_->transmissionBatch(upper, n, pT);
        for (size_t k = 0; k < n; ++k)
            in[first + k]->emplace(wi[first + k], incident(wi[first + k], pT[k]));
    }
}

void YarnBsdf::evalPdfBatch(const BsdfIncident* const* in, const Vec3* wo, size_t count,
                            BsdfEval* out) const {
    Vec3 wiUpper[kBatchChunk], woUpper[kBatchChunk];
    Rgb m[kBatchChunk];
    for (size_t first = 0; first < count; first += kBatchChunk) {
        const size_t n = std::min(kBatchChunk, count - first);
        for (size_t k = 0; k < n; ++k) {
            const YarnIncident& yarn = in[first + k]->get<YarnIncident>();
            wiUpper[k] = yarn.wi;
            woUpper[k] = upperSide(yarn, wo[first + k]);
        }
        model_->evalMBatch(wiUpper, woUpper, n, m);
        for (size_t k = 0; k < n; ++k)
            evalAndPdf(in[first + k]->get<YarnIncident>(), woUpper[k], &out[first + k].value,
                       &out[first + k].pdf, &m[k]);
    }
}

void YarnBsdf::sampleBatch(const BsdfIncident* const* in, const BsdfSampleInput* u, Rng* const* rng,
                           size_t count, BsdfSample* out) const {
    // The directions first (each from its own generator, in order), then S_M
    // at the continuous lobes' directions in one batch.
    size_t index[kBatchChunk];
    int lobe[kBatchChunk];
    Vec3 wiUpper[kBatchChunk], woUpper[kBatchChunk];
    Rgb m[kBatchChunk];
    for (size_t first = 0; first < count; first += kBatchChunk) {
        const size_t n = std::min(kBatchChunk, count - first);
        size_t continuous = 0;
        for (size_t k = 0; k < n; ++k) {
            const YarnIncident& yarn = in[first + k]->get<YarnIncident>();
            if (u[first + k][0] < yarn.pickT) {
                out[first + k] = transmissionSample(*in[first + k]);
                continue;
            }
            const YarnDirectionSample d = sampler_->sample(yarn, u[first + k], *rng[first + k]);
            index[continuous] = first + k;
            lobe[continuous] = d.lobe;
            wiUpper[continuous] = yarn.wi;
            woUpper[continuous] = d.wo;
            ++continuous;
        }
        model_->evalMBatch(wiUpper, woUpper, continuous, m);
        for (size_t c = 0; c < continuous; ++c) {
            const YarnIncident& yarn = in[index[c]]->get<YarnIncident>();
            BsdfEval e;
            evalAndPdf(yarn, woUpper[c], &e.value, &e.pdf, &m[c]);
            out[index[c]] =
                BsdfSample::fromEval(yarn.mirrored ? mirrored(woUpper[c]) : woUpper[c], e, lobe[c]);
        }
    }
}

}  // namespace weft
