#include "weft/yarn/yarn_bsdf.h"

#include <algorithm>

#include "weft/core/math.h"
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
      sampler_(makeYarnSampler(options.sampling, model, model_)),
      exitOffset_(model.exitOffset ? std::make_shared<const ExitOffsetTable>(*model.exitOffset)
                                   : nullptr) {}

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
    sampler_->prepareSurfaceShare(in);
    return in;
}

void YarnBsdf::evalAndPdf(const YarnIncident& in, const Vec3& wo, Rgb* value, double* density,
                          const Rgb* m, Part part) const {
    const FiberBcsdf::Angles out =
        value || sampler_->pdfNeedsOutAngles() ? model_->outAngles(wo) : FiberBcsdf::Angles{};
    if (value) {
        // S_R alone takes S_M as 0: the M network is not run.
        const Rgb noM(0.0);
        if (part == Part::Surface) m = &noM;
        const YarnComponents parts =
            m ? model_->components(in, wo, out, *m) : model_->components(wo, in, out);
        *value = part == Part::Surface ? Rgb(0.0) : parts.m;
        if (model_->hasReflection() && part != Part::Spread) *value += parts.r;
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

// The exit spread (yarn_bsdf.h, "Exit offsets").

namespace {

// Both branches keep a share, so that each part's weight stays bounded.
constexpr double kMinimumBranch = 0.05;

double surfaceBranch(const YarnIncident& in) {
    return std::clamp(in.surfaceShare, kMinimumBranch, 1.0 - kMinimumBranch);
}

}  // namespace

void YarnBsdf::prepareSpread(const Rgb& importance, YarnIncident& in) const {
    in.spreadChannel = Rgb(0.0);
    if (!exitOffset_ || in.mirrored || !(in.pickT < 1)) return;
    in.exitCell = static_cast<int>(exitOffsetCell(in.wi));
    Rgb p;
    for (int c = 0; c < 3; ++c)
        p[c] = exitOffset_->hasDensity(static_cast<size_t>(in.exitCell), c) ? importance[c] : 0.0;
    const double sum = p.r + p.g + p.b;
    if (sum > 0) in.spreadChannel = p / sum;
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
        q[c] = c == channel ? o.pdf : exitOffset_->pdf(cell, c, o.dz, o.dpsi);
        mixture += p[c] * q[c];
    }
    SpreadOffset offset;
    offset.dz = o.dz;
    offset.dpsi = o.dpsi;
    offset.weight = mixture > 0 ? q / mixture : Rgb(0.0);
    return offset;
}

BsdfEval YarnBsdf::evalSurface(const BsdfIncident& in, const Vec3& wo) const {
    const YarnIncident& yarn = in.get<YarnIncident>();
    BsdfEval e;
    evalAndPdf(yarn, wo, &e.value, &e.pdf, nullptr, Part::Surface);
    e.pdf *= surfaceBranch(yarn);
    return e;
}

BsdfEval YarnBsdf::spreadPart(const YarnIncident& in, const Vec3& woExit, const Rgb* m) const {
    BsdfEval e;
    evalAndPdf(in, woExit, &e.value, &e.pdf, m, Part::Spread);
    e.pdf *= 1.0 - surfaceBranch(in);
    return e;
}

BsdfEval YarnBsdf::evalSpread(const BsdfIncident& in, const Vec3& woExit) const {
    return spreadPart(in.get<YarnIncident>(), woExit, nullptr);
}

bool YarnBsdf::eventDirection(const YarnIncident& in, const BsdfSampleInput& u, Rng& rng,
                              bool* spread, YarnDirectionSample* d) const {
    *spread = false;
    if (u[0] < in.pickT) return false;
    // The rest of u[0] picks the branch; rescaled onto [pickT, 1) again, it
    // drives the sampler as in sample().
    const double rhoS = surfaceBranch(in);
    const double v = std::clamp((u[0] - in.pickT) / (1.0 - in.pickT), 0.0, kOneMinusEpsilon);
    *spread = v >= rhoS;
    const double w = *spread ? (v - rhoS) / (1.0 - rhoS) : v / rhoS;
    const BsdfSampleInput branch = {
        in.pickT + (1.0 - in.pickT) * std::clamp(w, 0.0, kOneMinusEpsilon), u[1], u[2]};
    *d = sampler_->sample(in, branch, rng);
    return true;
}

SpreadSample YarnBsdf::eventSample(const YarnIncident& in, bool spread,
                                   const YarnDirectionSample& d, const Rgb* m) const {
    BsdfEval e;
    if (spread) {
        e = spreadPart(in, d.wo, m);
    } else {
        evalAndPdf(in, d.wo, &e.value, &e.pdf, nullptr, Part::Surface);
        e.pdf *= surfaceBranch(in);
    }
    SpreadSample out;
    out.spread = spread;
    out.sample = BsdfSample::fromEval(d.wo, e, spread ? kLobeM : kLobeR);
    return out;
}

SpreadSample YarnBsdf::sampleEvent(const BsdfIncident& in, const BsdfSampleInput& u,
                                   Rng& rng) const {
    const YarnIncident& yarn = in.get<YarnIncident>();
    bool spread;
    YarnDirectionSample d;
    if (!eventDirection(yarn, u, rng, &spread, &d)) return {false, transmissionSample(in)};
    return eventSample(yarn, spread, d, nullptr);
}

void YarnBsdf::evalSpreadBatch(const BsdfIncident* const* in, const Vec3* woExit, size_t count,
                               BsdfEval* out) const {
    Vec3 wiUpper[kBatchChunk];
    Rgb m[kBatchChunk];
    for (size_t first = 0; first < count; first += kBatchChunk) {
        const size_t n = std::min(kBatchChunk, count - first);
        for (size_t k = 0; k < n; ++k) wiUpper[k] = in[first + k]->get<YarnIncident>().wi;
        model_->evalMBatch(wiUpper, woExit + first, n, m);
        for (size_t k = 0; k < n; ++k)
            out[first + k] =
                spreadPart(in[first + k]->get<YarnIncident>(), woExit[first + k], &m[k]);
    }
}

void YarnBsdf::sampleEventBatch(const BsdfIncident* const* in, const BsdfSampleInput* u,
                                Rng* const* rng, size_t count, SpreadSample* out) const {
    // The branches and directions first (each from its own generator), then
    // S_M at the spread branch's directions in one batch.
    size_t index[kBatchChunk];
    bool spread[kBatchChunk];
    YarnDirectionSample d[kBatchChunk];
    Vec3 wiUpper[kBatchChunk], woUpper[kBatchChunk];
    Rgb m[kBatchChunk];
    for (size_t first = 0; first < count; first += kBatchChunk) {
        const size_t n = std::min(kBatchChunk, count - first);
        size_t continuous = 0, spreading = 0;
        for (size_t k = 0; k < n; ++k) {
            const YarnIncident& yarn = in[first + k]->get<YarnIncident>();
            if (!eventDirection(yarn, u[first + k], *rng[first + k], &spread[continuous],
                                &d[continuous])) {
                out[first + k] = {false, transmissionSample(*in[first + k])};
                continue;
            }
            index[continuous] = first + k;
            if (spread[continuous]) {
                wiUpper[spreading] = yarn.wi;
                woUpper[spreading++] = d[continuous].wo;
            }
            ++continuous;
        }
        model_->evalMBatch(wiUpper, woUpper, spreading, m);
        for (size_t c = 0, s = 0; c < continuous; ++c)
            out[index[c]] = eventSample(in[index[c]]->get<YarnIncident>(), spread[c], d[c],
                                        spread[c] ? &m[s++] : nullptr);
    }
}

}  // namespace weft
