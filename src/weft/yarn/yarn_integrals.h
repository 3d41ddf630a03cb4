// weft/yarn/yarn_integrals.h — integrals of the yarn BSDF over outgoing directions.
//
// For one incident direction wi, by the product Gauss-Legendre rule of
// yarn/sphere_rule.h (about 12,000 nodes; `refinement` divides every panel
// width: the tests check that 1 agrees with 3). Used by `weft yarn check`, the
// fit's energy calibration and the energy tests.
#pragma once

#include <vector>

#include "weft/core/math.h"
#include "weft/core/rgb.h"
#include "weft/core/vec.h"
#include "weft/yarn/sphere_rule.h"
#include "weft/yarn/yarn_bsdf.h"

namespace weft {

struct DirectionalIntegrals {
    double pT = 0;  // P(T | wi): the delta lobe's share
    Rgb r, m;       // integrals of S_R and S_M (as the BSDF evaluates them) over the sphere
    Rgb albedo() const { return r + m + Rgb(pT); }

    // Variance proxies for the continuous part, f = channel mean of R + M:
    // relative second moments  V_p = integral of f^2 / p  /  (integral of f)^2
    // (the mean squared weight f/p of an estimator of the integral of f drawing wo
    // from p, in units of the squared integral; 1 is a perfect sampler).
    double secondMomentYarn = 0;     // p = pdf() / (1 - P(T|wi)): sample()'s continuous part
    double secondMomentUniform = 0;  // p = 1 / (4 pi)
    double secondMomentCosine = 0;   // p = |cos theta_o| / (2 pi): cosine-weighted on each
                                     // hemisphere, each picked with probability 1/2

    // sample()'s weight w = eval / pdf on luminance (core/rgb.h), T lobe
    // included (picked with probability P_T = lobeProbabilities(wi).t, weight
    // P(T) / P_T): the numbers that decide a path tracer's variance at this wi.
    double albedoLuminance = 0;     // P(T) + integral of luminance(R + M)
    double weightMean = 0;          // E[w] = P(T) + that integral where pdf > 0
    double weightSecondMoment = 0;  // E[w^2] = P(T)^2 / P_T + integral of luminance^2 / pdf
    double weightMax = 0;           // the largest w at the quadrature nodes and P(T) / P_T

    // The same per colour channel (w_c = eval_c / pdf): a sampler that follows
    // luminance can leave one channel's weight heavy-tailed (blue counts 0.07).
    Rgb channelAlbedo;        // P(T) + integral of (R + M)_c
    Rgb channelWeightMean;    // E[w_c]
    Rgb channelWeightSecond;  // E[w_c^2]
    Rgb channelWeightMax;     // the largest w_c

    // A channel whose albedo is at least half the brightest's: a dark
    // channel's paths end within a bounce or two, so the spread of its
    // weights hardly reaches an image (`weft yarn check` reports the others).
    static constexpr double kBrightChannel = 0.5;
    bool brightChannel(int c) const {
        return channelAlbedo[c] > 0 &&
               channelAlbedo[c] >= kBrightChannel * channelAlbedo.maxComponent();
    }
    double channelSecondMomentRatio(int c) const {
        return channelWeightMean[c] > 0 ? channelWeightSecond[c] / sqr(channelWeightMean[c]) : 0.0;
    }
};

// `secondMoments` false leaves the variance proxies and weights at 0 (and skips the pdf):
// the energies alone, as the fit's energy calibration needs them.
DirectionalIntegrals integrateDirections(const YarnBsdf& bsdf, const Vec3& wi, int refinement = 1,
                                         bool secondMoments = true);

// The nodes of that rule (yarn-frame directions) and their weights, for tests.
SphereRule yarnSphereRule(const YarnBsdf& bsdf, const Vec3& wi, int refinement = 1);

}  // namespace weft
