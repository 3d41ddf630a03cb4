// weft/yarn/appearance_table.h — a colour model's appearance at greys, and its
// inverse: the fiber colour C_TT that looks a given colour (yarn_appearance.h
// defines the appearance and computes the table; docs/colour.md, "Colour by
// appearance").
//
// Channel c of a colour model depends on C_TT,c alone, so the appearance of
// grey C_TT = g gives every channel's curve A_c(g) at once. The table holds
// it at greys uniform in u = sqrt(-ln C_TT) over the model's colour range;
// between them a monotone cubic (Fritsch-Carlson) in u, inverted per channel
// by bisection. The model file keeps it under "appearance" (version 4,
// docs/model-format.md).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "weft/core/rgb.h"

namespace weft {

// A conditioned model's appearance at greys across its colour range.
struct AppearanceTable {
    static constexpr int kDefaultNodes = 49;  // 8 per interval of the fit's 7 calibration nodes
    static constexpr int kMaxNodes = 257;     // the most a model file may hold
    // The largest appearance a file may hold: 1 for a lossless yarn, and a
    // fitted model's own error may put a channel a little above.
    static constexpr double kMaxAppearance = 1.1;
    std::vector<double> cTT;      // node greys, decreasing (u = sqrt(-ln C_TT) increasing)
    std::vector<Rgb> appearance;  // A at each node, per channel

    // The appearance of channel c for C_TT,c = cTT (within the table's range).
    double appearanceAt(int channel, double cTT) const;
    Rgb appearanceAt(const Rgb& cTT) const;
    // The brightest and the darkest appearance of channel c: at the colour
    // range's ends, C_TT = hi (the first node) and lo (the last).
    double brightest(int channel) const { return appearance.front()[channel]; }
    double darkest(int channel) const { return appearance.back()[channel]; }

    // The C_TT whose appearance is `linear` (each channel in [0, 1]).
    // InputError naming `what` when a channel is out of reach: the message gives
    // the channel, the value asked, the range the material reaches (linear and
    // sRGB) and the model's colour range.
    Rgb cTTFor(const Rgb& linear, const std::string& what) const;

    // {"c_tt": [...], "rgb": [[r, g, b], ...]}; the reader checks sizes, finite
    // values (appearance in [0, kMaxAppearance]), C_TT strictly decreasing in
    // (0, 1] and no channel brighter at a darker node (InputError naming
    // `source` and the key).
    nlohmann::json toJson() const;
    static AppearanceTable fromJson(const nlohmann::json& j, const std::string& source);
    void validate(const std::string& what) const;
};

}  // namespace weft
