// weft/yarn/exit_offset_table.h — where a ply's multiply scattered light
// leaves it, as a model carries it (issue 47, item 2; docs/exit-point.md).
//
// Per incident cell (core/exit_offset.h) and channel, a piecewise-constant
// density q_c(dz, dpsi | cell) over the offset of the exit point from the
// entry point: dz along the axis in ply radii, dpsi around it in [-pi, pi).
// Its bins have edges of their own (Edges): fine near no offset, wide in the
// heavy axial tails, every edge on the gather's grid of finer bins, which
// fromHistogram merges. The mass the gather put beyond the outermost axial
// edges (at most 0.3 % of a preset's M light, bench/results/exit-distance.md)
// is left out and the rest renormalised. A cell and channel without M light
// has no density (hasDensity false): its light leaves where it entered.
//
// A bin's mass is an integer (kMassScale for a whole cell and channel when
// the table is made from a histogram): model.json stores exactly these, so a
// table read from a file samples and evaluates bit for bit as the one the
// fit made. sample() inverts the running sums of the masses (binary search),
// uniform within the bin; pdf() is exactly the density it draws from, per
// unit dz dpsi.
//
// The file form (model.json "exit_offset", docs/model-format.md):
//   {"incident": {"theta_bands": 4, "phi_bands": 8},
//    "dz_edges": [...] (ply radii), "dpsi_edges_pi": [...] (units of pi, -1 to 1),
//    "masses": [cell][channel][bin] (integers, bins dz-major)}
#pragma once

#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "weft/core/exit_offset.h"

namespace weft {

class ExitOffsetTable {
  public:
    // The masses of one cell and channel sum to this when made from a histogram.
    static constexpr uint32_t kMassScale = 1000000;

    // Bin edges, strictly increasing: dz in ply radii, dpsi in units of pi
    // from -1 to 1 (so that the file holds them exactly).
    struct Edges {
        std::vector<double> dz, dpsiPi;
    };
    // The fit's default: |dz| at 0, 1/8, 1/4, 1/2, 3/4, 1, 1.5, 2, 3, 4, 6, 8
    // (22 bins: the measured spread is 0.3-1.9 R with a long tail) and |dpsi|
    // at 0, 1/16, 1/8, 1/4, 3/8, 1/2, 3/4, 1 pi (14 bins).
    static Edges defaultEdges();

    ExitOffsetTable() = default;
    // `histogram`: the gather's (kExitOffsetCells, kExitOffsetSlots, 3) M
    // weights (gather.h GatherResult::exitOffset), each finite and >= 0;
    // `edges` on its grid (dz multiples of kExitOffsetAxialWidth within its
    // axial range, dpsi multiples of 2 / kExitOffsetAroundBins, -1 to 1).
    // InputError naming `what` otherwise.
    static ExitOffsetTable fromHistogram(const std::vector<double>& histogram, const Edges& edges,
                                         const std::string& what);

    // The file form above; the reader names `source` and the JSON path of a
    // bad value (InputError).
    nlohmann::json toJson() const;
    static ExitOffsetTable fromJson(const nlohmann::json& j, const std::string& source,
                                    const std::string& path);

    const Edges& edges() const { return edges_; }
    int axialBins() const { return static_cast<int>(edges_.dz.size()) - 1; }
    int aroundBins() const { return static_cast<int>(edges_.dpsiPi.size()) - 1; }
    bool hasDensity(size_t cell, int channel) const;
    // A bin's mass over its cell and channel's total (0 without density).
    double probability(size_t cell, int channel, int axialBin, int aroundBin) const;

    struct Offset {
        double dz = 0, dpsi = 0;
        double pdf = 0;  // per unit dz dpsi; 0 for a cell without density (offset 0)
        int axialBin = -1, aroundBin = -1;  // the bin it lies in (-1 without density)
    };
    // u1 picks the bin and dz within it, u2 dpsi within it; both in [0, 1).
    Offset sample(size_t cell, int channel, double u1, double u2) const;
    double pdf(size_t cell, int channel, double dz, double dpsi) const;
    // pdf() within one bin, found once: every channel's bins are the same, so
    // a sample's bin gives the other channels' densities at it without a search.
    double binDensity(size_t cell, int channel, int axialBin, int aroundBin) const;

    size_t memoryBytes() const;

  private:
    static ExitOffsetTable fromMasses(Edges edges, const std::vector<uint32_t>& masses);
    size_t bins() const { return static_cast<size_t>(axialBins()) * aroundBins(); }
    // Running sums of the masses of a cell and channel: bins() + 1 numbers from 0.
    const uint32_t* runningOf(size_t cell, int channel) const;
    double binArea(int axialBin, int aroundBin) const;

    Edges edges_;
    std::vector<double> dpsiEdges_;  // edges_.dpsiPi in radians
    std::vector<uint32_t> running_;
};

}  // namespace weft
