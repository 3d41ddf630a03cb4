// weft/fit/colour_basis.h — how a ply's RDM_M changes with the fiber colour C_TT,
// and the colour functions (yarn/colour_basis.h) fitted to it.
//
// From an any-colour gather (gather/colour_paths.h), a cell's RDM_M in one
// channel is sum_paths W0 C_TT^k = sum_k h_k exp(-k s), s = -log C_TT: the
// Laplace transform of the cell's TT-event histogram, so its logarithm is a
// smooth convex function of s. A colour-conditioned M model writes it as
//     log RDM_M,c(wi, wo; C_TT,c) ~ sum_j a_jc(wi, wo) phi_j(s_c),  j < K,
// with one network for the coefficients a (evaluated once per direction
// pair) and K fixed functions phi of the colour, shared by every cell and
// channel. phi_0 = 1; phi_1..phi_{K-1} are the leading principal directions
// of the cells' centred log-RDM over a grid of colours (the rank-K
// approximation that is best in the energy-weighted least-squares sense).
// They are tabulated at `nodes` points uniform in s over the colour range
// and interpolated linearly in s.
//
// Measured on a 1M-path gabardine any-colour gather (fitColourBasis, C_TT
// in [0.3, 0.999], 33 nodes; mean / worst over the nodes of the coarse-grid
// relative L2 of each cell's best fit in the basis, all channels):
//   K = 2: 7.1% / 69%   K = 3: 1.6% / 12%   K = 4: 0.73% / 1.9%
//   K = 6: 0.07% / 0.31%   K = 8: 0.01% / 0.07%
// (a Legendre polynomial basis in s needs one or two more functions for the
// same error).
#pragma once

#include <cstdint>
#include <vector>

#include "weft/gather/gather.h"
#include "weft/gather/rdm.h"
#include "weft/yarn/colour_basis.h"

namespace weft {

struct ColourBasisFit {
    ColourBasis basis;
    // Relative L2 (over the coarse cells and channels, as fit/metrics.h) of
    // the best approximation of each cell's log RDM_M in the basis, per node.
    std::vector<double> nodeError;
    double meanError = 0, worstError = 0;
    int64_t rows = 0;  // coarse cells x channels that entered the fit
};

// The basis of `functions` functions (2 .. kMaxFunctions) over `range` from
// the M paths of an any-colour gather with `bins` and per-incident-bin path
// counts `count`, pooled to the coarse error grid of fit/metrics.h.
ColourBasisFit fitColourBasis(const std::vector<ColourPath>& paths, const RdmBins& bins,
                              const std::vector<int64_t>& count, const ColourRange& range,
                              int functions, int nodes = 33);

}  // namespace weft
