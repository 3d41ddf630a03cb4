#include "weft/yarn/cosine_sampler.h"

#include <cmath>

#include "weft/core/math.h"
#include "weft/core/sampling.h"

namespace weft {

void CosineYarnSampler::prepare(const SurfaceFiberAngles&, YarnIncident& in) const {
    in.pickT = in.pT;
}

double CosineYarnSampler::pdf(const YarnIncident& in, const Vec3& wo,
                              const FiberBcsdf::Angles&) const {
    // Cosine about n on the side of wo, each side with probability 1/2.
    return (1.0 - in.pT) * std::fabs(wo.z) * (0.5 * kInvPi);
}

YarnDirectionSample CosineYarnSampler::sample(const YarnIncident& in, const BsdfSampleInput& u,
                                              Rng&) const {
    // The rest of u[0], rescaled to [0, 1), picks the side of the surface.
    const double uSide = (u[0] - in.pT) / (1.0 - in.pT);
    Vec3 o = sampleCosineHemisphere(u[1], u[2]);
    if (!(uSide < 0.5)) o.z = -o.z;
    return {o, kYarnLobeM};
}

YarnLobeProbabilities CosineYarnSampler::lobeProbabilities(const YarnIncident& in) const {
    return {in.pT, 0.0, 1.0 - in.pT};
}

}  // namespace weft
