// weft/fit/metrics.h — the one error metric of every fit and check report.
//
// Issue 5: fine RDM maps are noisy, so maps are compared after pooling to a
// coarse grid (default 11 x 45 x 15 x 30). Fine incident bin i goes to the
// coarse bin containing its centre, and likewise for outgoing bins. The
// pooled value of coarse cell (I, O) is the radiance averaged over the cell:
//     P[I, O] = sum_{i in I} sum_{o in O} v[i, o] W_o / (n_I * W_O),
// with W_o the solid angle of fine outgoing bin o, W_O = sum_{o in O} W_o and
// n_I the number of fine incident bins in I. Then
//     relL2 = sqrt( sum_{I, O, c} W_O (P_fit - P_ref)^2 / sum_{I, O, c} W_O P_ref^2 ),
// where in relL2 W_O is the coarse bin's own solid angle (equal to the sum when the
// fine grid refines the coarse one, as the default 22,90,45,90 does).
#pragma once

#include <vector>

#include "weft/core/rgb.h"
#include "weft/gather/rdm.h"
#include "weft/gather/rdm_io.h"

namespace weft {

// Coarse grid with the same layout as RdmBins; defaults from the issue.
inline constexpr RdmBins kCoarseErrorBins{11, 45, 15, 30};

// Fine -> coarse bin of the same kind, through the fine bin's centre direction.
std::vector<size_t> incidentMap(const RdmBins& fine, const RdmBins& coarse);
std::vector<size_t> outgoingMap(const RdmBins& fine, const RdmBins& coarse);

// Pools a (TI, PI, TO, PO, 3) map to `coarse` (same layout), as above.
std::vector<double> poolRdm(const std::vector<float>& map, const RdmBins& fine,
                            const RdmBins& coarse = kCoarseErrorBins);

// The relative L2 error of `fit` against `reference` (both fine maps on `fine`).
double coarseRelativeL2(const std::vector<float>& fit, const std::vector<float>& reference,
                        const RdmBins& fine, const RdmBins& coarse = kCoarseErrorBins);

// Energy of a (TI, PI, TO, PO, 3) map per incident bin and channel:
// sum_o v[i, o] dOmega_o (an RDM's directional albedo of that component).
std::vector<Rgb> incidentEnergies(const std::vector<float>& map, const RdmBins& bins);
// The energy of a whole map: the channel mean of incidentEnergies averaged
// over incident bins weighted by their solid angle.
double mapEnergy(const std::vector<float>& map, const RdmBins& bins);

// Error of a P(T | wi) map (at incident bin centres) against the gather's:
// RMS over incident bins weighted by the path counts (bins with few paths
// weigh less, as their variance says), and unweighted.
struct TransmissionError {
    double weighted = 0, unweighted = 0;
};
TransmissionError transmissionError(const std::vector<double>& pT, const RdmData& rdm);

}  // namespace weft
