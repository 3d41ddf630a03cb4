#include "weft/yarn/appearance_table.h"

#include <algorithm>
#include <cmath>

#include "weft/core/error.h"
#include "weft/core/image.h"
#include "weft/core/json_message.h"
#include "weft/core/json_reader.h"
#include "weft/core/math.h"

namespace weft {

namespace {

double u_of(double cTT) { return std::sqrt(-std::log(cTT)); }

// Fritsch-Carlson slopes of the points (x, y), x increasing: a cubic Hermite
// interpolant through them that is monotone wherever the data are.
std::vector<double> monotoneSlopes(const std::vector<double>& x, const std::vector<double>& y) {
    const size_t n = x.size();
    std::vector<double> secant(n - 1), slope(n);
    for (size_t k = 0; k + 1 < n; ++k) secant[k] = (y[k + 1] - y[k]) / (x[k + 1] - x[k]);
    slope[0] = secant[0];
    slope[n - 1] = secant[n - 2];
    for (size_t k = 1; k + 1 < n; ++k) {
        if (secant[k - 1] * secant[k] <= 0) {
            slope[k] = 0;
            continue;
        }
        const double h0 = x[k] - x[k - 1], h1 = x[k + 1] - x[k];
        const double w1 = 2 * h1 + h0, w2 = h1 + 2 * h0;
        slope[k] = (w1 + w2) / (w1 / secant[k - 1] + w2 / secant[k]);
    }
    return slope;
}

double hermite(const std::vector<double>& x, const std::vector<double>& y,
               const std::vector<double>& slope, double at) {
    const size_t n = x.size();
    at = std::clamp(at, x.front(), x.back());
    size_t k = std::upper_bound(x.begin(), x.end(), at) - x.begin();
    k = std::clamp<size_t>(k, 1, n - 1) - 1;
    const double h = x[k + 1] - x[k], t = (at - x[k]) / h;
    const double t2 = t * t, t3 = t2 * t;
    return (2 * t3 - 3 * t2 + 1) * y[k] + (t3 - 2 * t2 + t) * h * slope[k] +
           (-2 * t3 + 3 * t2) * y[k + 1] + (t3 - t2) * h * slope[k + 1];
}

const char* kChannelName[3] = {"red", "green", "blue"};

// Rounded for messages: 4 decimals of a linear value, 3 of its sRGB encoding.
std::string linearText(double linear) { return formatNumber(std::round(1e4 * linear) / 1e4); }
std::string srgbText(double linear) {
    return formatNumber(std::round(1e3 * linearToSrgb(linear)) / 1e3);
}

}  // namespace

double AppearanceTable::appearanceAt(int channel, double cTT) const {
    std::vector<double> x(this->cTT.size()), y(x.size());
    for (size_t i = 0; i < x.size(); ++i) {
        x[i] = u_of(this->cTT[i]);
        y[i] = appearance[i][channel];
    }
    return hermite(x, y, monotoneSlopes(x, y), u_of(cTT));
}

Rgb AppearanceTable::appearanceAt(const Rgb& c) const {
    return Rgb(appearanceAt(0, c.r), appearanceAt(1, c.g), appearanceAt(2, c.b));
}

Rgb AppearanceTable::cTTFor(const Rgb& linear, const std::string& what) const {
    Rgb out;
    for (int c = 0; c < 3; ++c) {
        const double want = linear[c];
        if (!(want >= 0 && want <= 1))
            throw InputError(what + ": " + kChannelName[c] + " " + formatNumber(want) +
                             " is out of range: allowed [0, 1]");
        // Within half a thousandth of an end counts as that end: the
        // table's own interpolation error is larger.
        const double lo = darkest(c), hi = brightest(c), slack = 5e-4;
        if (want < lo - slack || want > hi + slack)
            throw InputError(
                what + ": " + kChannelName[c] + " " + formatNumber(want) + " (linear; sRGB " +
                srgbText(want) + ") is out of reach for this material: its " + kChannelName[c] +
                " looks between " + linearText(lo) + " and " + linearText(hi) + " (sRGB " +
                srgbText(lo) + " to " + srgbText(hi) + ") for C_TT in the model's colour range [" +
                formatNumber(cTT.back()) + ", " + formatNumber(cTT.front()) + "]");
        std::vector<double> x(cTT.size()), y(x.size());
        for (size_t i = 0; i < x.size(); ++i) {
            x[i] = u_of(cTT[i]);
            y[i] = appearance[i][c];
        }
        const std::vector<double> slope = monotoneSlopes(x, y);
        // The interpolant decreases in u: bisect.
        double a = x.front(), b = x.back();
        for (int it = 0; it < 100 && b - a > 1e-15; ++it) {
            const double mid = 0.5 * (a + b);
            (hermite(x, y, slope, mid) > want ? a : b) = mid;
        }
        out[c] = std::clamp(std::exp(-sqr(0.5 * (a + b))), cTT.back(), cTT.front());
    }
    return out;
}

void AppearanceTable::validate(const std::string& what) const {
    if (cTT.size() < 2 || appearance.size() != cTT.size())
        throw InputError(what + ": expected at least 2 nodes, as many colours as C_TT values");
    for (size_t i = 0; i < cTT.size(); ++i) {
        if (!(cTT[i] > 0 && cTT[i] <= 1))
            throw InputError(what + ": c_tt[" + std::to_string(i) + "] " + formatNumber(cTT[i]) +
                             " is out of range: allowed (0, 1]");
        if (i > 0 && !(cTT[i] < cTT[i - 1]))
            throw InputError(what + ": c_tt must decrease strictly, node " + std::to_string(i));
        for (int c = 0; c < 3; ++c) {
            const double a = appearance[i][c];
            // Physically at most 1; a fitted model's own error (within the
            // energy guard's quadrature) may put a lossless channel a
            // little above.
            if (!(a >= 0 && a <= kMaxAppearance))
                throw InputError(what + ": rgb[" + std::to_string(i) + "][" + std::to_string(c) +
                                 "] " + formatNumber(a) + " is out of range: allowed [0, " +
                                 formatNumber(kMaxAppearance) + "]");
            // Never brighter at a darker node: the inverse is unique up to a plateau.
            if (i > 0 && a > appearance[i - 1][c])
                throw InputError(what + ": the " + kChannelName[c] +
                                 " appearance does not darken with C_TT between C_TT " +
                                 formatNumber(cTT[i - 1]) + " and " + formatNumber(cTT[i]) + " (" +
                                 formatNumber(appearance[i - 1][c]) + ", " + formatNumber(a) + ")");
        }
    }
}

nlohmann::json AppearanceTable::toJson() const {
    nlohmann::json rgb = nlohmann::json::array();
    for (const Rgb& a : appearance) rgb.push_back({a.r, a.g, a.b});
    return {{"c_tt", cTT}, {"rgb", rgb}};
}

AppearanceTable AppearanceTable::fromJson(const nlohmann::json& j, const std::string& source) {
    JsonObjectReader r(j, source, "appearance");
    r.allowKeys({"c_tt", "rgb"});
    const nlohmann::json& c = r.value("c_tt");
    const nlohmann::json& rgb = r.value("rgb");
    if (!c.is_array() || !rgb.is_array() || c.size() != rgb.size() || c.size() < 2 ||
        c.size() > static_cast<size_t>(kMaxNodes))
        r.fail("expected \"c_tt\" and \"rgb\" arrays of the same length, 2 to " +
               std::to_string(kMaxNodes));
    AppearanceTable table;
    for (size_t i = 0; i < c.size(); ++i) {
        table.cTT.push_back(readJsonNumber(c[i], source, jsonIndexPath(r.pathOf("c_tt"), i),
                                           NumberRange::openClosed(0, 1)));
        if (!rgb[i].is_array() || rgb[i].size() != 3)
            r.fail("rgb", "element " + std::to_string(i) + " is not an array of 3 numbers");
        const std::string row = jsonIndexPath(r.pathOf("rgb"), i);
        Rgb a;
        for (int ch = 0; ch < 3; ++ch)
            a[ch] = readJsonNumber(rgb[i][ch], source, jsonIndexPath(row, static_cast<size_t>(ch)),
                                   NumberRange::closed(0, kMaxAppearance));
        table.appearance.push_back(a);
    }
    table.validate(source + ": appearance");
    return table;
}

}  // namespace weft
