#include "weft/fit/colour_targets.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "weft/core/error.h"

namespace weft {

ColourTargets::ColourTargets(const std::vector<ColourPath>& paths, const RdmBins& bins,
                             const std::vector<int64_t>& count, ColourPath::Kind kind,
                             CellIndex index)
    : bins_(bins), sparse_(index == CellIndex::Sparse) {
    const size_t nIn = bins.incidentCount(), nOut = bins.outgoingCount();
    if (count.size() != nIn) throw std::logic_error("ColourTargets: count does not match the bins");
    // Counting sort by cell: stable, so entries stay in path order within a cell.
    std::vector<uint32_t> perCell(nIn * nOut + 1, 0);
    size_t m = 0;
    for (const ColourPath& p : paths)
        if (p.kind == kind) ++perCell[p.incidentBin * nOut + p.outgoingBin + 1], ++m;
    if (m > UINT32_MAX) throw InputError("more than 2^32 recorded paths of one kind");
    for (size_t k = 1; k < perCell.size(); ++k) perCell[k] += perCell[k - 1];
    if (sparse_) {
        for (size_t cell = 0; cell + 1 < perCell.size(); ++cell)
            if (perCell[cell + 1] > perCell[cell]) {
                sparseCells_.push_back(static_cast<uint32_t>(cell));
                cellStart_.push_back(perCell[cell]);
            }
        cellStart_.push_back(static_cast<uint32_t>(m));
    } else {
        cellStart_ = perCell;
    }
    entries_.resize(m);
    for (const ColourPath& p : paths) {
        if (p.kind != kind) continue;
        const size_t cell = p.incidentBin * nOut + p.outgoingBin;
        const double norm = 1.0 / (static_cast<double>(count[p.incidentBin]) *
                                   bins.outgoingSolidAngle(p.outgoingBin));
        Entry& e = entries_[perCell[cell]++];
        e.ttEvents = p.ttEvents;
        for (int c = 0; c < 3; ++c) e.weight[c] = static_cast<float>(p.weight[c] * norm);
    }
}

std::pair<uint32_t, uint32_t> ColourTargets::cellEntries(size_t cell) const {
    if (!sparse_) return {cellStart_[cell], cellStart_[cell + 1]};
    const auto it = std::lower_bound(sparseCells_.begin(), sparseCells_.end(), cell);
    if (it == sparseCells_.end() || *it != cell) return {0, 0};
    const size_t k = static_cast<size_t>(it - sparseCells_.begin());
    return {cellStart_[k], cellStart_[k + 1]};
}

Rgb ColourTargets::value(size_t i, size_t o, const Rgb& cTT) const {
    const auto [begin, end] = cellEntries(i * bins_.outgoingCount() + o);
    Rgb v;
    for (uint32_t k = begin; k < end; ++k) {
        const Entry& e = entries_[k];
        for (int c = 0; c < 3; ++c) v[c] += e.weight[c] * std::pow(cTT[c], e.ttEvents);
    }
    return v;
}

std::vector<float> ColourTargets::map(const Rgb& cTT) const {
    const size_t nIn = bins_.incidentCount(), nOut = bins_.outgoingCount();
    std::vector<float> out(nIn * nOut * 3);
    tbb::parallel_for(size_t(0), nIn, [&](size_t i) {
        for (size_t o = 0; o < nOut; ++o) {
            const Rgb v = value(i, o, cTT);
            for (int c = 0; c < 3; ++c) out[(i * nOut + o) * 3 + c] = static_cast<float>(v[c]);
        }
    });
    return out;
}

}  // namespace weft
