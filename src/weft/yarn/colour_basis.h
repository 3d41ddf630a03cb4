// weft/yarn/colour_basis.h — the colour functions of a colour-conditioned M model.
//
// A conditioned model (fit/colour_basis.h, docs/colour.md) writes the M lobe
// of channel c as
//     M_c(wi, wo; C_TT,c) = exp( sum_j a_jc(wi, wo) phi_j(s_c) ),  s = -ln C_TT,c,
// with one network for the coefficients a (3K outputs, a_jc at index 3 j + c)
// and K functions phi of the colour shared by every direction and channel:
// phi_0 = 1, the others tabulated at nodes uniform in s over the model's
// colour range and interpolated linearly in s. Colours outside the range are
// clamped to it.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "weft/core/rgb.h"
#include "weft/yarn/network.h"

namespace weft {

// The fiber colours a conditioned model covers, per channel.
struct ColourRange {
    double lo = 0.3, hi = 0.999;
    // InputError naming `what` unless 0 < lo < hi <= 1.
    void validate(const std::string& what) const;
    double sOf(double cTT) const;  // -log(cTT), cTT clamped into [lo, hi]
};

// "LO,HI" with 0 < LO < HI <= 1; InputError naming `flag` otherwise.
ColourRange parseColourRange(const std::string& text, const std::string& flag);

class ColourBasis {
  public:
    static constexpr int kMaxFunctions = 12;

    ColourBasis() = default;
    // table[j][g]: phi_j at node g (s uniform from -log(hi) to -log(lo));
    // table[0] must be all ones. InputError naming `source` otherwise.
    ColourBasis(ColourRange range, std::vector<std::vector<double>> table,
                const std::string& source = "colour basis");

    const ColourRange& range() const { return range_; }
    int functions() const { return static_cast<int>(table_.size()); }
    int nodes() const { return table_.empty() ? 0 : static_cast<int>(table_[0].size()); }
    const std::vector<std::vector<double>>& table() const { return table_; }
    // s of node g.
    double nodeS(int g) const;

    // phi_0..phi_{K-1} at C_TT = cTT (clamped into the range), into phi[0..K).
    void eval(double cTT, double* phi) const;

    nlohmann::json toJson() const;
    static ColourBasis fromJson(const nlohmann::json& j, const std::string& source);

  private:
    ColourRange range_;
    std::vector<std::vector<double>> table_;
    double sLo_ = 0, sStep_ = 1;
};

// The ordinary M network (3 outputs, exp output) of a conditioned one (3K
// outputs, identity) at one colour: the last layer's rows of each channel
// combined with phi_j(C_TT,c). Its output equals conditionedM for every input.
NetworkWeights foldColourIntoNetwork(const NetworkWeights& conditioned, const ColourBasis& basis,
                                     const Rgb& colour);

// M of one direction pair for `colour`: the 3K coefficients of the network
// (index 3 j + c) combined with the basis per channel, then exp.
Rgb conditionedM(const float* coefficients, const ColourBasis& basis, const Rgb& colour);

}  // namespace weft
