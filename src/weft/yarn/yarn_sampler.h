// weft/yarn/yarn_sampler.h — how the yarn BSDF draws its outgoing directions.
//
// YarnBsdf::sample (yarn_bsdf.h) picks the delta T lobe (wo = -wi) with a
// probability the sampler sets, P_T = YarnIncident::pickT, and otherwise asks
// the sampler for a direction of the continuous part R + M; its pdf is the
// sampler's density, so eval / pdf is the weight of every strategy. Three
// strategies, each a YarnSampler in its own file with its sample/pdf pair:
//   tabulated (tabulated_sampler.h, the default): follows the model itself
//     through a table built when the model loads;
//   fitted    (fitted_sampler.h): the paper's lobes, eq. 9-11;
//   cosine    (cosine_sampler.h): the ablation "cosine sampling" of paper Fig. 5.
// Each continuous pdf integrates to 1 - P_T over the sphere. Directions are in
// the yarn frame, in the upper-hemisphere convention of the incident
// (yarn_incident.h: a lower wi is mirrored, and so are the returned wo).
#pragma once

#include <cstddef>
#include <memory>
#include <string>

#include "weft/core/bsdf.h"
#include "weft/core/rng.h"
#include "weft/core/vec.h"
#include "weft/fiber/fiber_bcsdf.h"
#include "weft/yarn/yarn_incident.h"

namespace weft {

class YarnEvaluator;
struct YarnModel;

// The strategies (above).
enum class YarnSampling { Tabulated, Fitted, Cosine };
// "tabulated", "fitted" or "cosine"; InputError naming `what` and the allowed values otherwise.
YarnSampling parseYarnSampling(const std::string& name, const std::string& what);
const char* yarnSamplingName(YarnSampling sampling);

// The lobes a yarn BSDF sample reports (BsdfSample::lobe).
inline constexpr int kYarnLobeT = 0;
inline constexpr int kYarnLobeR = 1;
inline constexpr int kYarnLobeM = 2;

// The probabilities with which sample() draws from each lobe: the delta T,
// the R part and the M part (for tabulated sampling: q_R and the table).
struct YarnLobeProbabilities {
    double t = 0, r = 0, m = 0;
};

// A direction of the continuous part and the lobe it is reported as.
struct YarnDirectionSample {
    Vec3 wo;
    int lobe = kYarnLobeM;
};

class YarnSampler {
  public:
    virtual ~YarnSampler() = default;

    virtual YarnSampling kind() const = 0;

    // Whether prepare() reads the model's part of the incident and wi's
    // surface angles; false: it needs P(T|wi) alone, so that a lone pdf(wi,
    // wo) skips the calibration and the energy guard.
    virtual bool usesModelScales() const = 0;
    // Fills the sampler's part of `in` (pickT and what else it keeps); the
    // model's part is set (yarn_evaluator.h).
    virtual void prepare(const SurfaceFiberAngles& surface, YarnIncident& in) const = 0;

    // Whether pdf() reads `out` (wo's surface-fiber angles, which eval computes anyway).
    virtual bool pdfNeedsOutAngles() const { return false; }
    // Density of sample()'s continuous part at wo per unit solid angle, 1 - P_T
    // included; `out` = YarnEvaluator::outAngles(wo) when pdfNeedsOutAngles().
    virtual double pdf(const YarnIncident& in, const Vec3& wo,
                       const FiberBcsdf::Angles& out) const = 0;
    // A direction of the continuous part, for u[0] >= in.pickT (the rest of
    // u[0] picks among the sampler's parts; u[1], u[2] the direction; `rng`
    // feeds rejection steps).
    virtual YarnDirectionSample sample(const YarnIncident& in, const BsdfSampleInput& u,
                                       Rng& rng) const = 0;
    virtual YarnLobeProbabilities lobeProbabilities(const YarnIncident& in) const = 0;

    // Bytes of the sampler's tables.
    virtual size_t memoryBytes() const = 0;
};

// The sampler of that kind for a model (`model` of one colour, the one
// `evaluator` was built from, guard included: the tabulated sampler follows
// it, and keeps it).
std::unique_ptr<const YarnSampler> makeYarnSampler(
    YarnSampling kind, const YarnModel& model, const std::shared_ptr<const YarnEvaluator>& evaluator);

}  // namespace weft
