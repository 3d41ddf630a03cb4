// weft/fit/colour_targets.h — RDM_M (or RDM_R) of any fiber colour, cell by
// cell, from an any-colour gather's recorded paths (gather/colour_paths.h).
//
// The M paths sorted by cell (incident bin, outgoing bin): the value of a
// cell for C_TT is sum over its paths of W0_c C_TT,c^k / count(i) /
// solidAngle(o), exactly what an ordinary gather of that colour holds in
// rdm_m (docs/design.md 5), for any colour and without a map per colour. With the
// paper's 16M paths over 8M cells a cell holds a few paths, so a value costs a
// few multiplications: the training of a colour-conditioned M network draws
// a new colour for every sample. Memory: 16 bytes per M path and 4 per cell;
// with CellIndex::Sparse (a family's many small gathers, fit/family_fit.h)
// 8 per cell that holds a path, found by binary search.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "weft/core/rgb.h"
#include "weft/gather/gather.h"
#include "weft/gather/rdm.h"

namespace weft {

class ColourTargets {
  public:
    // The M paths of `paths` (others are skipped; with kind = R, the R paths
    // and so RDM_R) for a gather with `bins` and per-incident-bin path counts `count`.
    enum class CellIndex { Dense, Sparse };
    ColourTargets(const std::vector<ColourPath>& paths, const RdmBins& bins,
                  const std::vector<int64_t>& count, ColourPath::Kind kind = ColourPath::M,
                  CellIndex index = CellIndex::Dense);

    const RdmBins& bins() const { return bins_; }
    size_t paths() const { return entries_.size(); }

    // RDM_M (RDM_R) of cell (i, o) for the colour C_TT.
    Rgb value(size_t incidentBin, size_t outgoingBin, const Rgb& cTT) const;
    // The whole map (TI, PI, TO, PO, 3) for C_TT, as rdm_m.npy (rdm_r.npy) holds it.
    std::vector<float> map(const Rgb& cTT) const;

  private:
    struct Entry {
        int32_t ttEvents;
        float weight[3];  // W0 / count(i) / solidAngle(o)
    };
    // Entries [first, second) of a cell.
    std::pair<uint32_t, uint32_t> cellEntries(size_t cell) const;

    RdmBins bins_;
    // Dense: nIn * nOut + 1 offsets into entries_. Sparse: one offset per cell
    // of sparseCells_ (the cells that hold entries, ascending) and the end.
    std::vector<uint32_t> cellStart_;
    std::vector<uint32_t> sparseCells_;
    bool sparse_ = false;
    std::vector<Entry> entries_;
};

}  // namespace weft
