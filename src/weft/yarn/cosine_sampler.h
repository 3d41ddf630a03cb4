// weft/yarn/cosine_sampler.h — cosine sampling of the yarn BSDF: the ablation
// "cosine sampling" of paper Fig. 5 (docs/fit.md).
//
// Keeps the delta T lobe, picked with P_T = P(T|wi) (weight 1), but draws the
// continuous part from a cosine density about n on either side of the
// surface, each with probability 1/2 (the yarn BSDF covers the whole sphere:
// M also transmits):
//   pdf(wi, wo) = (1 - P(T|wi)) |wo.z| / (2 pi),
// which integrates to 1 - P(T|wi) over the sphere. u[0] picks T, then
// (rescaled) the side; u[1], u[2] the direction. Samples report the M lobe
// (the continuous part).
#pragma once

#include "weft/yarn/yarn_sampler.h"

namespace weft {

class CosineYarnSampler final : public YarnSampler {
  public:
    YarnSampling kind() const override { return YarnSampling::Cosine; }
    bool usesModelScales() const override { return false; }
    void prepare(const SurfaceFiberAngles& surface, YarnIncident& in) const override;
    double pdf(const YarnIncident& in, const Vec3& wo,
               const FiberBcsdf::Angles& out) const override;
    YarnDirectionSample sample(const YarnIncident& in, const BsdfSampleInput& u,
                               Rng& rng) const override;
    YarnLobeProbabilities lobeProbabilities(const YarnIncident& in) const override;
    size_t memoryBytes() const override { return sizeof(*this); }
};

}  // namespace weft
