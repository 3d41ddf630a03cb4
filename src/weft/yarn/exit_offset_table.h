// weft/yarn/exit_offset_table.h — where a ply's multiply scattered light
// leaves it, as a model carries it (issue 47, item 2; docs/exit-point.md).
//
// Per incident cell (core/exit_offset.h) and channel, a piecewise-constant
// density q_c(dz, dpsi | cell) over the offset of the exit point from the
// entry point: dz along the axis in [-axialRange, axialRange) ply radii,
// dpsi around it in [-pi, pi). Its bins are the gather's, merged
// `axialMerge` x `aroundMerge` at a time (fromHistogram); the mass the
// gather put beyond the axial range (at most 0.3 % of a preset's M light,
// bench/results/exit-distance.md) is left out and the rest renormalised. A
// cell and channel without M light has no density (hasDensity false): its
// light leaves where it entered.
//
// sample() inverts the cumulative masses (rows of dz by binary search, then
// the dpsi bins of that row), uniform within a bin; pdf() is exactly the
// density it draws from, per unit dz dpsi.
//
// Step 2 of the design: built and tested here; not yet read from or written
// to model.json, nor used by the renderer.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "weft/core/exit_offset.h"

namespace weft {

class ExitOffsetTable {
  public:
    ExitOffsetTable() = default;
    // `histogram`: the gather's (kExitOffsetCells, kExitOffsetSlots, 3) M
    // weights (gather.h GatherResult::exitOffset), each finite and >= 0;
    // the merges divide kExitOffsetAxialBins and kExitOffsetAroundBins.
    // InputError naming `what` otherwise.
    static ExitOffsetTable fromHistogram(const std::vector<double>& histogram, int axialMerge,
                                         int aroundMerge, const std::string& what);

    int axialBins() const { return axialBins_; }
    int aroundBins() const { return aroundBins_; }
    double axialWidth() const { return axialWidth_; }
    double axialRange() const { return 0.5 * axialBins_ * axialWidth_; }
    double aroundWidth() const;

    bool hasDensity(size_t cell, int channel) const;

    struct Offset {
        double dz = 0, dpsi = 0;
        double pdf = 0;  // per unit dz dpsi; 0 for a cell without density (offset 0)
    };
    // u1 picks the bin and dz within it, u2 dpsi within it; both in [0, 1).
    Offset sample(size_t cell, int channel, double u1, double u2) const;
    double pdf(size_t cell, int channel, double dz, double dpsi) const;

    size_t memoryBytes() const;

  private:
    // The bin of (dz, dpsi), or -1 outside the range.
    long binOf(double dz, double dpsi) const;
    const float* cdfOf(size_t cell, int channel) const;

    int axialBins_ = 0, aroundBins_ = 0;
    double axialWidth_ = 0;
    // Per cell and channel: the running sum of the bins' probabilities in
    // row-major order (bins + 1 numbers from 0; the last about 1, or 0 for no
    // density); a bin's probability is the difference of two.
    std::vector<float> cdf_;
};

}  // namespace weft
