#include "weft/yarn/yarn_integrals.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "weft/core/math.h"

namespace weft {

SphereRule yarnSphereRule(const YarnBsdf& bsdf, const Vec3& wi, int refinement) {
    return surfaceFiberSphereRule(bsdf.model().frame(),
                                  radians(bsdf.model().rLobe().fiber().params().betaRDeg), wi, refinement);
}

DirectionalIntegrals integrateDirections(const YarnBsdf& bsdf, const Vec3& wi, int refinement,
                                         bool secondMoments) {
    const SphereRule rule = yarnSphereRule(bsdf, wi, refinement);
    DirectionalIntegrals out;
    out.pT = bsdf.transmission(wi);
    const double continuousShare = 1.0 - out.pT;
    double integral = 0, yarn = 0, uniform = 0, cosine = 0;
    double lumIntegral = 0, lumCovered = 0, lumSecond = 0, weightMax = 0;
    Rgb channelIntegral, channelCovered, channelSecond, channelMax;
    for (size_t k = 0; k < rule.directions.size(); ++k) {
        const Vec3& wo = rule.directions[k];
        const double w = rule.weights[k];
        const YarnComponents c = bsdf.components(wi, wo);
        out.r += c.r * w;
        out.m += c.m * w;
        if (!secondMoments) continue;
        const double f = (c.r + c.m).average();
        if (f == 0) continue;
        integral += f * w;
        const double pdf = bsdf.pdf(wi, wo);
        const double pYarn = continuousShare > 0 ? pdf / continuousShare : 0.0;
        const Rgb value = c.r + c.m;
        const double lum = luminance(value);
        lumIntegral += lum * w;
        channelIntegral += value * w;
        if (pdf > 0) {
            lumCovered += lum * w;
            lumSecond += lum * lum / pdf * w;
            weightMax = std::max(weightMax, lum / pdf);
            channelCovered += value * w;
            channelSecond += value * value * (w / pdf);
            for (int ch = 0; ch < 3; ++ch)
                channelMax[ch] = std::max(channelMax[ch], value[ch] / pdf);
        }
        yarn += pYarn > 0 ? f * f / pYarn * w : std::numeric_limits<double>::infinity();
        uniform += f * f * (4 * kPi) * w;
        const double pCosine = std::fabs(wo.z) / kTwoPi;
        cosine += pCosine > 0 ? f * f / pCosine * w : std::numeric_limits<double>::infinity();
    }
    if (secondMoments) {
        // T is picked with probability P_T and weighs P(T) / P_T.
        const double pickT = bsdf.lobeProbabilities(wi).t;
        const double weightT = pickT > 0 ? out.pT / pickT : 0.0;
        out.albedoLuminance = out.pT + lumIntegral;
        out.weightMean = out.pT + lumCovered;
        out.weightSecondMoment = out.pT * weightT + lumSecond;
        out.weightMax = std::max(weightT, weightMax);
        out.channelAlbedo = Rgb(out.pT) + channelIntegral;
        out.channelWeightMean = Rgb(out.pT) + channelCovered;
        out.channelWeightSecond = Rgb(out.pT * weightT) + channelSecond;
        for (int ch = 0; ch < 3; ++ch) out.channelWeightMax[ch] = std::max(weightT, channelMax[ch]);
    }
    const double squared = integral * integral;
    if (squared > 0) {
        out.secondMomentYarn = yarn / squared;
        out.secondMomentUniform = uniform / squared;
        out.secondMomentCosine = cosine / squared;
    }
    return out;
}

}  // namespace weft
