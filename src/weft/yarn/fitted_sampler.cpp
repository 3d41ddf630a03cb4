#include "weft/yarn/fitted_sampler.h"

#include <algorithm>

#include "weft/core/math.h"
#include "weft/yarn/yarn_evaluator.h"

namespace weft {

FittedYarnSampler::FittedYarnSampler(const YarnModel& model, const YarnEvaluator& evaluator)
    : lobes_(model.fiber, model.rLobe.tiltDeg, model.sampling),
      kappaR_(evaluator.hasReflection() ? model.sampling.kappaR : 0.0) {}

void FittedYarnSampler::prepare(const SurfaceFiberAngles&, YarnIncident& in) const {
    in.pickT = in.pT;
}

double FittedYarnSampler::pdf(const YarnIncident& in, const Vec3& wo,
                              const FiberBcsdf::Angles&) const {
    // Paper eq. 10-11: the continuous mixture p_R pdf_R + p_M pdf_M.
    const double pR = (1.0 - in.pT) * kappaR_, pM = (1.0 - in.pT) * (1.0 - kappaR_);
    double d = 0;
    if (pR > 0) d += pR * lobes_.pdfR(in.wi, wo);
    if (pM > 0) d += pM * lobes_.pdfM(in.wi, wo);
    return d;
}

YarnDirectionSample FittedYarnSampler::sample(const YarnIncident& in, const BsdfSampleInput& u,
                                              Rng& rng) const {
    const double pT = in.pT;
    const double pR = (1.0 - pT) * kappaR_, pM = (1.0 - pT) * (1.0 - kappaR_);
    if (u[0] < pT + pR || !(pM > 0)) return {lobes_.sampleR(in.wi, u[1], u[2]), kYarnLobeR};
    // The rest of u[0], rescaled to [0, 1), picks the cone or the uniform part of pdf_M.
    const double uLobe = std::clamp((u[0] - pT - pR) / pM, 0.0, kOneMinusEpsilon);
    return {lobes_.sampleM(in.wi, uLobe, u[1], u[2], rng), kYarnLobeM};
}

YarnLobeProbabilities FittedYarnSampler::lobeProbabilities(const YarnIncident& in) const {
    return {in.pT, (1.0 - in.pT) * kappaR_, (1.0 - in.pT) * (1.0 - kappaR_)};
}

}  // namespace weft
