#include "weft/yarn/exit_offset_table.h"

#include <algorithm>
#include <cmath>

#include "weft/core/error.h"
#include "weft/core/json_message.h"
#include "weft/core/math.h"

namespace weft {

ExitOffsetTable ExitOffsetTable::fromHistogram(const std::vector<double>& histogram, int axialMerge,
                                               int aroundMerge, const std::string& what) {
    if (histogram.size() != kExitOffsetCells * kExitOffsetSlots * 3)
        throw InputError(what + ": " + std::to_string(histogram.size()) + " numbers, expected " +
                         std::to_string(kExitOffsetCells * kExitOffsetSlots * 3) +
                         " (cells x slots x 3, core/exit_offset.h)");
    if (!(axialMerge >= 1 && kExitOffsetAxialBins % axialMerge == 0 && aroundMerge >= 1 &&
          kExitOffsetAroundBins % aroundMerge == 0))
        throw InputError(what + ": bins merged " + std::to_string(axialMerge) + " x " +
                         std::to_string(aroundMerge) + " must divide " +
                         std::to_string(kExitOffsetAxialBins) + " x " +
                         std::to_string(kExitOffsetAroundBins));
    ExitOffsetTable t;
    t.axialBins_ = kExitOffsetAxialBins / axialMerge;
    t.aroundBins_ = kExitOffsetAroundBins / aroundMerge;
    t.axialWidth_ = kExitOffsetAxialWidth * axialMerge;
    const size_t bins = static_cast<size_t>(t.axialBins_) * t.aroundBins_;
    t.cdf_.assign(kExitOffsetCells * 3 * (bins + 1), 0.0f);
    std::vector<double> merged(bins);
    for (size_t cell = 0; cell < kExitOffsetCells; ++cell)
        for (int c = 0; c < 3; ++c) {
            std::fill(merged.begin(), merged.end(), 0.0);
            double total = 0;
            for (int i = 0; i < kExitOffsetAxialBins; ++i)
                for (int j = 0; j < kExitOffsetAroundBins; ++j) {
                    const size_t slot = static_cast<size_t>(i) * kExitOffsetAroundBins + j;
                    const double w = histogram[(cell * kExitOffsetSlots + slot) * 3 + c];
                    if (!(std::isfinite(w) && w >= 0))
                        throw InputError(what + ": cell " + std::to_string(cell) + ", slot " +
                                         std::to_string(slot) + ", channel " + std::to_string(c) +
                                         " is " + formatNumber(w) +
                                         " (weights are finite and >= 0)");
                    merged[static_cast<size_t>(i / axialMerge) * t.aroundBins_ + j / aroundMerge] +=
                        w;
                    total += w;
                }
            if (!(total > 0)) continue;
            // Running sums of the probabilities; sample() and pdf() both use
            // these floats, so pdf is exactly the density sample draws from.
            float* cdf = &t.cdf_[(cell * 3 + c) * (bins + 1)];
            double running = 0;
            for (size_t k = 0; k < bins; ++k) {
                running += merged[k] / total;
                cdf[k + 1] = static_cast<float>(running);
            }
        }
    return t;
}

double ExitOffsetTable::aroundWidth() const { return kTwoPi / aroundBins_; }

bool ExitOffsetTable::hasDensity(size_t cell, int channel) const {
    const size_t bins = static_cast<size_t>(axialBins_) * aroundBins_;
    return !cdf_.empty() && cdfOf(cell, channel)[bins] > 0;
}

const float* ExitOffsetTable::cdfOf(size_t cell, int channel) const {
    const size_t bins = static_cast<size_t>(axialBins_) * aroundBins_;
    return &cdf_[(cell * 3 + static_cast<size_t>(channel)) * (bins + 1)];
}

long ExitOffsetTable::binOf(double dz, double dpsi) const {
    const double a = (dz + axialRange()) / axialWidth_;
    const double b = (dpsi + kPi) / aroundWidth();
    if (!(a >= 0 && a < axialBins_ && b >= 0 && b < aroundBins_)) return -1;
    return static_cast<long>(a) * aroundBins_ + std::min(static_cast<int>(b), aroundBins_ - 1);
}

ExitOffsetTable::Offset ExitOffsetTable::sample(size_t cell, int channel, double u1,
                                                double u2) const {
    Offset o;
    if (!hasDensity(cell, channel)) return o;
    const size_t bins = static_cast<size_t>(axialBins_) * aroundBins_;
    const float* cdf = cdfOf(cell, channel);
    const double target = u1 * cdf[bins];
    // The last bin whose running sum is <= target and whose mass is > 0.
    size_t k = static_cast<size_t>(std::upper_bound(cdf + 1, cdf + bins + 1, target) - (cdf + 1));
    k = std::min(k, bins - 1);
    while (k > 0 && !(cdf[k + 1] > cdf[k])) --k;
    while (k + 1 < bins && !(cdf[k + 1] > cdf[k])) ++k;
    const double width = cdf[k + 1] - cdf[k];
    const double f = std::clamp((target - cdf[k]) / width, 0.0, 1.0);
    const int i = static_cast<int>(k / aroundBins_), j = static_cast<int>(k % aroundBins_);
    o.dz = -axialRange() + (i + f) * axialWidth_;
    o.dpsi = -kPi + (j + u2) * aroundWidth();
    o.pdf = width / cdf[bins] / (axialWidth_ * aroundWidth());
    return o;
}

double ExitOffsetTable::pdf(size_t cell, int channel, double dz, double dpsi) const {
    if (!hasDensity(cell, channel)) return 0.0;
    const long k = binOf(dz, dpsi);
    if (k < 0) return 0.0;
    const size_t bins = static_cast<size_t>(axialBins_) * aroundBins_;
    const float* cdf = cdfOf(cell, channel);
    return (cdf[k + 1] - cdf[k]) / cdf[bins] / (axialWidth_ * aroundWidth());
}

size_t ExitOffsetTable::memoryBytes() const { return cdf_.size() * sizeof(float); }

}  // namespace weft
