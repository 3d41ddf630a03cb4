// weft/fiber/von_mises.h — the azimuthal von Mises lobe of the fiber model.
//
// N_TT(phi) = exp(kappa cos(phi - mean)) / (2 pi I0(kappa)), kappa = 1 / gamma^2
// with gamma in radians (docs/design.md 3, paper eq. 3). Evaluated with the scaled
// Bessel function so that narrow lobes (large kappa) do not overflow. Sampling
// is Best & Fisher's (1979) exact rejection algorithm, rewritten so that no
// step cancels catastrophically when kappa is large.
#pragma once

#include "weft/core/rng.h"

namespace weft {

// The von Mises distribution of concentration kappa about mean 0, with its
// normaliser and sampling constants computed once.
class VonMises {
public:
    explicit VonMises(double kappa);
    double kappa() const { return kappa_; }
    // Density at angle x measured from the mean.
    double pdf(double x) const;
    // The density given cos(x), for callers that have the cosine already.
    double pdfOfCos(double cosX) const;
    // An angle in [-pi, pi] measured from the mean, exactly von Mises
    // distributed. u drives the first proposal; rng supplies the rest.
    double sample(double u, Rng& rng) const;

private:
    double kappa_, invNorm_;
    double rMinus1_;  // Best & Fisher's r - 1, computed once per kappa
};

}  // namespace weft
