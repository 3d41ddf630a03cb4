// weft/yarn/yarn_bsdf.h — the aggregated yarn BSDF (paper 4, eq. 6-11; docs/design.md 7).
//
// S(wi, wo) = S_T + S_R + S_M for one ply material, from a fitted model.json,
// behind the BSDF contract of core/bsdf.h. Three parts, each in its own file:
//   the model's value      YarnEvaluator (yarn_evaluator.h): P(T|wi), S_R, S_M,
//                          the energy calibration and the EnergyGuard (energy_guard.h);
//   the sampling strategy  a YarnSampler (yarn_sampler.h): tabulated (default),
//                          fitted (paper eq. 10-11) or cosine (an ablation);
//   the incident state     YarnIncident (yarn_incident.h), prepared once per wi.
//
//   eval(wi, wo)  the continuous part R + M (the delta T is never returned).
//   pdf(wi, wo)   the sampler's density of the continuous part per unit solid
//                 angle; it integrates to 1 - P_T over the sphere, P_T the
//                 probability of the T lobe (lobeProbabilities(wi).t).
//   sample(wi, u) picks T with P_T by u[0]: wo = -wi exactly, weight P(T|wi) /
//                 P_T (grey), pdf = 0, isDelta, lobe kLobeT; otherwise the
//                 sampler's direction (lobe kLobeR or kLobeM) with weight =
//                 eval / pdf, both from the one routine that eval() and pdf()
//                 use, so the sampler's parts are combined by one-sample MIS.
// Directions are unit vectors in the yarn shading frame of the ply hit: t =
// +x (ply tangent), b = +y, n = +z (outward normal), docs/design.md 2; the
// caller converts world directions with Frame(t, b, n).
//
// Exit offsets (a model with an "exit_offset" table, docs/exit-point.md):
// the BSDF is also an ExitSpread (core/bsdf.h). At an incident from above
// whose cell has M light in some channel, the event splits: the surface
// part S_T + S_R at the hit, the M part S_M at an exit point drawn from the
// table, S_M(wi, wo) with wo in the exit point's frame (the model's M lobe
// was fitted so). The offset: a channel c picked with p_c, 3/4 in
// proportion to the M light it carries (the path's importance times E_M in
// wi's cell times the factor on S_M) and 1/4 to the importance alone, among
// the channels with M light there; the offset from q_c, each channel
// weighted by q_c / sum_c' p_c' q_c' (one-sample MIS over channels). The
// continuation: T with P_T as sample() picks it; otherwise a direction wo
// from the whole continuous sampler (density pdf), then the surface branch
// with probability rho_S(wo) = S_R / (S_R + S_M) at wo (channels weighted by
// the path's importance; clamped to [0.05, 0.95]) or the spread branch, each
// weighting its part: S_R / (rho_S pdf), S_M / ((1 - rho_S) pdf). So
// evalSurface's density is rho_S(wo) pdf(wo) and evalSpread's (1 -
// rho_S(wo)) pdf(wo), and where S_R and S_M have one colour the
// continuation's weight is sample()'s (R + M) / pdf. Mirrored incidents
// (from inside), cells without M light and models without the table keep
// today's event.
//
// Incident directions below the surface (wi.z < 0): the networks were trained
// on the upper hemisphere only and a ply is never lit from inside, so the BSDF
// is made two-sided the way Mitsuba's `twosided` adapter does it: wi and wo are
// both mirrored through the surface plane (z -> -z) and the upper-hemisphere
// BSDF is used. eval, pdf and sample all do this, so they stay consistent;
// wi.z == 0 counts as upper.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "weft/core/bsdf.h"
#include "weft/core/rng.h"
#include "weft/yarn/yarn_evaluator.h"
#include "weft/yarn/yarn_incident.h"
#include "weft/yarn/yarn_model.h"
#include "weft/yarn/yarn_sampler.h"

namespace weft {

struct YarnBsdfOptions {
    bool energyGuard = true;  // scale S_M where the model's albedo exceeds 1 (energy_guard.h)
    YarnSampling sampling = YarnSampling::Tabulated;
};

class YarnBsdf final : public Bsdf, public ExitSpread {
  public:
    static constexpr int kLobeT = kYarnLobeT;
    static constexpr int kLobeR = kYarnLobeR;
    static constexpr int kLobeM = kYarnLobeM;

    // Validates the model once (YarnEvaluator; InputError naming `source`).
    // A colour-conditioned model (yarn_model.h) is rendered at its own
    // gathered colour, model.forColour(model.ownColourInRange()); pass
    // model.forColour(cTT) for another colour.
    explicit YarnBsdf(const YarnModel& model, const std::string& source = "yarn model",
                      const YarnBsdfOptions& options = {});
    // loadYarnModel(path), then the constructor with the path as source.
    static YarnBsdf load(const std::string& path, const YarnBsdfOptions& options = {});

    // The Bsdf interface (core/bsdf.h); the incident state is a YarnIncident,
    // so a slice (Bsdf::slice) pays for wi once; pdf(wi, wo) computes only
    // what the sampler's density needs (P(T) alone unless the sampling is
    // tabulated). sample(wi, u) draws rejection steps from bsdfSampleRng(u),
    // as FiberBcsdf does.
    using Bsdf::eval;
    using Bsdf::evalPdf;
    using Bsdf::pdf;
    using Bsdf::sample;
    void prepare(const Vec3& wi, BsdfIncident& in) const override;
    BsdfEval evalPdf(const BsdfIncident& in, const Vec3& wo) const override;
    Rgb eval(const BsdfIncident& in, const Vec3& wo) const override;
    double pdf(const BsdfIncident& in, const Vec3& wo) const override;
    double pdf(const Vec3& wi, const Vec3& wo) const override;
    BsdfSample sample(const BsdfIncident& in, const BsdfSampleInput& u, Rng& rng) const override;
    // The batches (core/bsdf.h), bit for bit the single calls: the T network
    // (prepare) and the M network (evalPdf, sample) run one query per SIMD
    // lane (FixedMlp::forwardBatch), the rest per query.
    void prepareBatch(const Vec3* wi, BsdfIncident* const* in, size_t count) const override;
    void evalPdfBatch(const BsdfIncident* const* in, const Vec3* wo, size_t count,
                      BsdfEval* out) const override;
    void sampleBatch(const BsdfIncident* const* in, const BsdfSampleInput* u, Rng* const* rng,
                     size_t count, BsdfSample* out) const override;
    bool batchesFaster() const override { return true; }
    const ExitSpread* exitSpread() const override { return exitOffset_ ? this : nullptr; }

    // ExitSpread (above; core/bsdf.h).
    bool splits(const BsdfIncident& in) const override;
    SpreadOffset sampleOffset(const BsdfIncident& in, const BsdfSampleInput& u) const override;
    BsdfEval evalSurface(const BsdfIncident& in, const Vec3& wo) const override;
    BsdfEval evalSpread(const BsdfIncident& in, const Vec3& woExit) const override;
    SpreadSample sampleEvent(const BsdfIncident& in, const BsdfSampleInput& u,
                             Rng& rng) const override;
    // Their batches run the M network one query per SIMD lane.
    void evalSurfaceBatch(const BsdfIncident* const* in, const Vec3* wo, size_t count,
                          BsdfEval* out) const override;
    void evalSpreadBatch(const BsdfIncident* const* in, const Vec3* woExit, size_t count,
                         BsdfEval* out) const override;
    void sampleEventBatch(const BsdfIncident* const* in, const BsdfSampleInput* u, Rng* const* rng,
                          size_t count, SpreadSample* out) const override;
    // The model's exit-offset table, or nullptr.
    const ExitOffsetTable* exitOffsets() const { return exitOffset_.get(); }

    // The networks, the energy guard's and the sampler's tables.
    size_t memoryBytes() const override;

    // P(T | wi) from the T network (0 for a naive model).
    double transmission(const Vec3& wi) const;
    // The parts of eval at one pair (T as P(T|wi), R and M as eval gives them).
    YarnComponents components(const Vec3& wi, const Vec3& wo) const;
    // The probabilities with which sample() draws T, R and M at wi.
    YarnLobeProbabilities lobeProbabilities(const Vec3& wi) const;

    const YarnEvaluator& model() const { return *model_; }
    const YarnSampler& sampler() const { return *sampler_; }
    YarnAblation ablation() const { return model_->ablation(); }
    YarnSampling sampling() const { return sampler_->kind(); }

    // This BSDF with the tabulated sampler built from its own evaluator
    // (shared, not built again): bit for bit YarnBsdf(model, source, {guard,
    // Tabulated}) of the model it was made from. weft view shades its first
    // look after a colour edit with fitted sampling, whose BSDF builds in
    // about half the time (the sampling table is the other half), then with
    // this (docs/view.md).
    std::unique_ptr<YarnBsdf> withTabulatedSampling() const;

  private:
    // The constructor proper, for a model of one colour.
    struct OneColour {};
    YarnBsdf(const YarnModel& model, const std::string& source, const YarnBsdfOptions& options,
             OneColour);

    // The incident state of wi: the model's part, then the sampler's.
    YarnIncident incident(const Vec3& wi) const;
    // The same with P(T) given: pT = transmission(wi).
    YarnIncident incident(const Vec3& wi, double pT) const;
    // eval and pdf at wo (mirrored with the incident): the one place where
    // both are computed. `m`: S_M at (in.wi, wo) when a batch computed it.
    void evalAndPdf(const YarnIncident& in, const Vec3& wo, Rgb* value, double* density,
                    const Rgb* m = nullptr) const;
    // The incident's exit-offset cell and channel probabilities (YarnIncident)
    // for a path of this importance.
    void prepareSpread(const Rgb& importance, YarnIncident& in) const;
    // A split event's parts at wo (the hit's or the exit point's frame, as
    // the incident's): S_R, S_M (`m`, or the M network's), the sampler's
    // continuous density, and the surface branch's probability there.
    struct SplitParts {
        Rgb r, m;
        double pdf = 0, surface = 0.5;
        // One branch's value and its density of reaching wo.
        BsdfEval part(bool spread) const;
    };
    SplitParts splitParts(const BsdfIncident& in, const Vec3& wo, const Rgb* m) const;
    // evalSurfaceBatch or evalSpreadBatch.
    void evalPartBatch(const BsdfIncident* const* in, const Vec3* wo, size_t count, bool spread,
                       BsdfEval* out) const;
    // sampleEvent after its continuous direction d: the branch (one number
    // from rng), its value and weight (`m`: S_M at d.wo, or the M network's).
    SpreadSample eventSample(const BsdfIncident& in, const YarnDirectionSample& d, const Rgb* m,
                             Rng& rng) const;

    // Immutable once built, so copies of the BSDF share them (the tabulated
    // sampler keeps the evaluator too).
    std::shared_ptr<const YarnEvaluator> model_;
    std::shared_ptr<const YarnSampler> sampler_;
    std::shared_ptr<const ExitOffsetTable> exitOffset_;  // the model's, or none
    // With the table: E_M per exit-offset cell (the M network's albedo at the
    // cell's central wi), for the offset's channel probabilities.
    std::shared_ptr<const std::vector<Rgb>> exitCellM_;
};

}  // namespace weft
