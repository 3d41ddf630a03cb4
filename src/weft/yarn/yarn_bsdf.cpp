#include "weft/yarn/yarn_bsdf.h"

#include <algorithm>
#include <vector>

#include "weft/core/math.h"
#include "weft/yarn/sphere_rule.h"
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

// The sample batches' common part: per chunk, each query's continuous
// direction first, in order, each from its own generator (the T lobe:
// finish(query, nullptr, nullptr) at once), then S_M at those directions in
// one batch, then finish(query, &direction, &m) for each of them.
template <typename Finish>
void sampleInChunks(const YarnSampler& sampler, const YarnEvaluator& model,
                    const BsdfIncident* const* in, const BsdfSampleInput* u, Rng* const* rng,
                    size_t count, Finish finish) {
    size_t index[kBatchChunk];
    YarnDirectionSample d[kBatchChunk];
    Vec3 wiUpper[kBatchChunk], woUpper[kBatchChunk];
    Rgb m[kBatchChunk];
    for (size_t first = 0; first < count; first += kBatchChunk) {
        const size_t n = std::min(kBatchChunk, count - first);
        size_t continuous = 0;
        for (size_t k = 0; k < n; ++k) {
            const YarnIncident& yarn = in[first + k]->get<YarnIncident>();
            if (u[first + k][0] < yarn.pickT) {
                finish(first + k, nullptr, nullptr);
                continue;
            }
            d[continuous] = sampler.sample(yarn, u[first + k], *rng[first + k]);
            index[continuous] = first + k;
            wiUpper[continuous] = yarn.wi;
            woUpper[continuous] = d[continuous].wo;
            ++continuous;
        }
        model.evalMBatch(wiUpper, woUpper, continuous, m);
        for (size_t c = 0; c < continuous; ++c) finish(index[c], &d[c], &m[c]);
    }
}

// E_M per exit-offset cell (the M network's albedo, no calibration or guard,
// at the cell's central incident direction; the energy guard's rule): how
// much light each channel's offset carries there, for the offset's channel
// probabilities.
std::vector<Rgb> exitCellAlbedoM(const YarnEvaluator& model) {
    const SphereRule rule = mLobeSphereRule(model.frame());
    std::vector<Rgb> albedo(kExitOffsetCells);
    std::vector<Rgb> m(rule.directions.size());
    for (int i = 0; i < kExitOffsetTheta; ++i)
        for (int j = 0; j < kExitOffsetPhi; ++j) {
            const Vec3 wi = sphericalDirection((i + 0.5) * kHalfPi / kExitOffsetTheta,
                                               -kPi + (j + 0.5) * kTwoPi / kExitOffsetPhi);
            model.evalMBatch(wi, rule.directions.data(), m.size(), m.data());
            Rgb sum(0.0);
            for (size_t k = 0; k < m.size(); ++k) sum += m[k] * rule.weights[k];
            albedo[exitOffsetCell(wi)] = sum;
        }
    return albedo;
}

}  // namespace

YarnBsdf::YarnBsdf(const YarnModel& model, const std::string& source,
                   const YarnBsdfOptions& options)
    : YarnBsdf(model.colour ? model.forColour(model.ownColourInRange(), source) : model, source,
               options, OneColour{}) {}

YarnBsdf::YarnBsdf(const YarnModel& model, const std::string& source,
                   const YarnBsdfOptions& options, OneColour)
    // `new`, not make_shared: the evaluator's networks are over-aligned (FixedMlp).
    : model_(new YarnEvaluator(model, source, options.energyGuard)),
      sampler_(makeYarnSampler(options.sampling, model, model_)),
      exitOffset_(model.exitOffset ? std::make_shared<const ExitOffsetTable>(*model.exitOffset)
                                   : nullptr) {
    if (exitOffset_)
        exitCellM_ = std::make_shared<const std::vector<Rgb>>(exitCellAlbedoM(*model_));
}

std::unique_ptr<YarnBsdf> YarnBsdf::withTabulatedSampling() const {
    auto bsdf = std::make_unique<YarnBsdf>(*this);
    bsdf->sampler_ = std::make_shared<TabulatedYarnSampler>(model_);
    return bsdf;
}

YarnBsdf YarnBsdf::load(const std::string& path, const YarnBsdfOptions& options) {
    return YarnBsdf(loadYarnModel(path), path, options);
}

size_t YarnBsdf::memoryBytes() const {
    return sizeof(*this) + model_->memoryBytes() + sampler_->memoryBytes() +
           (exitOffset_ ? exitOffset_->memoryBytes() : 0);
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
    const FiberBcsdf::Angles out =
        value || sampler_->pdfNeedsOutAngles() ? model_->outAngles(wo) : FiberBcsdf::Angles{};
    if (value) {
        const YarnComponents parts =
            m ? model_->components(in, wo, out, *m) : model_->components(wo, in, out);
        *value = parts.m;
        if (model_->hasReflection()) *value += parts.r;
    }
    if (density) *density = sampler_->pdf(in, wo, out);
}

void YarnBsdf::prepare(const Vec3& wi, BsdfIncident& in) const {
    YarnIncident yarn = incident(wi);
    prepareSpread(in.importance(), yarn);
    in.emplace(wi, yarn);
}

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
        for (size_t k = 0; k < n; ++k) {
            YarnIncident yarn = incident(wi[first + k], pT[k]);
            prepareSpread(in[first + k]->importance(), yarn);
            in[first + k]->emplace(wi[first + k], yarn);
        }
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
    sampleInChunks(*sampler_, *model_, in, u, rng, count,
                   [&](size_t k, const YarnDirectionSample* d, const Rgb* m) {
                       if (!d) {
                           out[k] = transmissionSample(*in[k]);
                           return;
                       }
                       const YarnIncident& yarn = in[k]->get<YarnIncident>();
                       BsdfEval e;
                       evalAndPdf(yarn, d->wo, &e.value, &e.pdf, m);
                       out[k] = BsdfSample::fromEval(yarn.mirrored ? mirrored(d->wo) : d->wo, e,
                                                     d->lobe);
                   });
}

// The exit spread (yarn_bsdf.h, "Exit offsets").

namespace {

// Both branches keep a share, so that each part's weight stays bounded.
constexpr double kMinimumBranch = 0.05;
// The exit offset's channel probabilities: this share by the importance alone
// (prepareSpread). Measured (docs/exit-point.md, "The offset's channel"): 0
// and 0.25 give the same noise within 6 %; 1 (the importance alone) 1.1-1.8
// times as much as 0.25.
constexpr double kDefensiveChannelShare = 0.25;

double weightedSum(const Rgb& weight, const Rgb& x) {
    return weight.r * x.r + weight.g * x.g + weight.b * x.b;
}

}  // namespace

void YarnBsdf::prepareSpread(const Rgb& importance, YarnIncident& in) const {
    in.spreadChannel = Rgb(0.0);
    if (!exitOffset_ || in.mirrored || !(in.pickT < 1)) return;
    in.exitCell = static_cast<int>(exitOffsetCell(in.wi));
    // Each channel in proportion to the M light it carries at wi (the path's
    // importance times E_M in wi's cell times the incident's factor on S_M),
    // mixed with the importance alone (a defensive share: every channel with
    // M light keeps a probability, so the channels' one-sample MIS stays
    // unbiased where E_M's estimate is low).
    Rgb p;
    for (int c = 0; c < 3; ++c)
        p[c] = exitOffset_->hasDensity(static_cast<size_t>(in.exitCell), c) ? importance[c] : 0.0;
    const double sum = p.r + p.g + p.b;
    if (!(sum > 0)) return;
    const Rgb carried = p * (*exitCellM_)[static_cast<size_t>(in.exitCell)] * in.mScale;
    const double total = carried.r + carried.g + carried.b;
    in.spreadChannel = total > 0 ? carried / total * (1.0 - kDefensiveChannelShare) +
                                       p / sum * kDefensiveChannelShare
                                 : p / sum;
}

bool YarnBsdf::splits(const BsdfIncident& in) const {
    return in.get<YarnIncident>().spreadChannel.maxComponent() > 0;
}

SpreadOffset YarnBsdf::sampleOffset(const BsdfIncident& in, const BsdfSampleInput& u) const {
    // A channel by the path's importance, then q_c; each channel's weight
    // over the mixture of the channels' densities.
    const YarnIncident& yarn = in.get<YarnIncident>();
    const Rgb& p = yarn.spreadChannel;
    const size_t cell = static_cast<size_t>(yarn.exitCell);
    const int channel = u[0] < p.r ? 0 : u[0] < p.r + p.g ? 1 : 2;
    const ExitOffsetTable::Offset o = exitOffset_->sample(cell, channel, u[1], u[2]);
    Rgb q;
    double mixture = 0;
    for (int c = 0; c < 3; ++c) {
        q[c] = c == channel ? o.pdf : exitOffset_->binDensity(cell, c, o.axialBin, o.aroundBin);
        mixture += p[c] * q[c];
    }
    SpreadOffset offset;
    offset.dz = o.dz;
    offset.dpsi = o.dpsi;
    offset.weight = mixture > 0 ? q / mixture : Rgb(0.0);
    return offset;
}

YarnBsdf::SplitParts YarnBsdf::splitParts(const BsdfIncident& incident, const Vec3& wo,
                                          const Rgb* m) const {
    const YarnIncident& in = incident.get<YarnIncident>();
    const FiberBcsdf::Angles out = model_->outAngles(wo);
    const YarnComponents parts =
        m ? model_->components(in, wo, out, *m) : model_->components(wo, in, out);
    SplitParts split;
    split.r = model_->hasReflection() ? parts.r : Rgb(0.0);
    split.m = parts.m;
    split.pdf = sampler_->pdf(in, wo, out);
    // The surface branch's probability at wo: S_R's share of S_R + S_M,
    // channels weighted by the path's importance.
    const double r = weightedSum(incident.importance(), split.r);
    const double all = r + weightedSum(incident.importance(), split.m);
    split.surface = std::clamp(all > 0 ? r / all : 0.5, kMinimumBranch, 1.0 - kMinimumBranch);
    return split;
}

BsdfEval YarnBsdf::SplitParts::part(bool spread) const {
    BsdfEval e;
    e.value = spread ? m : r;
    e.pdf = pdf * (spread ? 1.0 - surface : surface);
    return e;
}

BsdfEval YarnBsdf::evalSurface(const BsdfIncident& in, const Vec3& wo) const {
    return splitParts(in, wo, nullptr).part(false);
}

BsdfEval YarnBsdf::evalSpread(const BsdfIncident& in, const Vec3& woExit) const {
    return splitParts(in, woExit, nullptr).part(true);
}

SpreadSample YarnBsdf::eventSample(const BsdfIncident& in, const YarnDirectionSample& d,
                                   const Rgb* m, Rng& rng) const {
    const SplitParts split = splitParts(in, d.wo, m);
    SpreadSample out;
    out.spread = rng.uniform() >= split.surface;
    out.sample = BsdfSample::fromEval(d.wo, split.part(out.spread), out.spread ? kLobeM : kLobeR);
    return out;
}

SpreadSample YarnBsdf::sampleEvent(const BsdfIncident& in, const BsdfSampleInput& u,
                                   Rng& rng) const {
    const YarnIncident& yarn = in.get<YarnIncident>();
    if (u[0] < yarn.pickT) return {false, transmissionSample(in)};
    return eventSample(in, sampler_->sample(yarn, u, rng), nullptr, rng);
}

void YarnBsdf::evalPartBatch(const BsdfIncident* const* in, const Vec3* wo, size_t count,
                             bool spread, BsdfEval* out) const {
    Vec3 wiUpper[kBatchChunk];
    Rgb m[kBatchChunk];
    for (size_t first = 0; first < count; first += kBatchChunk) {
        const size_t n = std::min(kBatchChunk, count - first);
        for (size_t k = 0; k < n; ++k) wiUpper[k] = in[first + k]->get<YarnIncident>().wi;
        model_->evalMBatch(wiUpper, wo + first, n, m);
        for (size_t k = 0; k < n; ++k)
            out[first + k] = splitParts(*in[first + k], wo[first + k], &m[k]).part(spread);
    }
}

void YarnBsdf::evalSurfaceBatch(const BsdfIncident* const* in, const Vec3* wo, size_t count,
                                BsdfEval* out) const {
    evalPartBatch(in, wo, count, false, out);
}

void YarnBsdf::evalSpreadBatch(const BsdfIncident* const* in, const Vec3* woExit, size_t count,
                               BsdfEval* out) const {
    evalPartBatch(in, woExit, count, true, out);
}

void YarnBsdf::sampleEventBatch(const BsdfIncident* const* in, const BsdfSampleInput* u,
                                Rng* const* rng, size_t count, SpreadSample* out) const {
    // The branch after S_M's batch, from the query's own generator.
    sampleInChunks(*sampler_, *model_, in, u, rng, count,
                   [&](size_t k, const YarnDirectionSample* d, const Rgb* m) {
                       out[k] = d ? eventSample(*in[k], *d, m, *rng[k])
                                  : SpreadSample{false, transmissionSample(*in[k])};
                   });
}

}  // namespace weft
