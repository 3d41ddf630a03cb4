// weft/yarn/fitted_sampler.h — the paper's sampling of the yarn BSDF (paper
// 4.4, eq. 9-11; the model's "sampling" block, docs/model-format.md).
//
// Lobe probabilities p_T = P(T|wi), p_R = (1 - p_T) kappa_R and p_M = (1 -
// p_T)(1 - kappa_R), picked by u[0]; R and M directions from the fitted lobes
// of yarn_lobes.h (SamplingLobes: pdf_R on the upper half cone, pdf_M a cone
// lobe plus a uniform part), u[1], u[2] and, for the von Mises rejection
// steps, the generator; the density of the continuous part is the mixture
//   pdf(wi, wo) = p_R pdf_R(wi, wo) + p_M pdf_M(wi, wo)   (eq. 10),
// which integrates to 1 - P(T|wi). Without an R lobe (ablations) kappa_R = 0
// whatever the file says, so R is never sampled.
#pragma once

#include "weft/yarn/yarn_lobes.h"
#include "weft/yarn/yarn_sampler.h"

namespace weft {

class FittedYarnSampler final : public YarnSampler {
  public:
    // The model's sampling parameters (validated with the model).
    FittedYarnSampler(const YarnModel& model, const YarnEvaluator& evaluator);

    YarnSampling kind() const override { return YarnSampling::Fitted; }
    bool usesModelScales() const override { return false; }
    void prepare(const SurfaceFiberAngles& surface, YarnIncident& in) const override;
    double pdf(const YarnIncident& in, const Vec3& wo,
               const FiberBcsdf::Angles& out) const override;
    YarnDirectionSample sample(const YarnIncident& in, const BsdfSampleInput& u,
                               Rng& rng) const override;
    YarnLobeProbabilities lobeProbabilities(const YarnIncident& in) const override;
    size_t memoryBytes() const override { return sizeof(*this); }

    const SamplingLobes& lobes() const { return lobes_; }
    double kappaR() const { return kappaR_; }

  private:
    SamplingLobes lobes_;
    double kappaR_;  // 0 without an R lobe
};

}  // namespace weft
