#include "weft/yarn/colour_basis.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "weft/core/error.h"
#include "weft/core/json_reader.h"
#include "weft/core/text_parse.h"

namespace weft {

void ColourRange::validate(const std::string& what) const {
    if (!(lo > 0 && lo < hi && hi <= 1))
        throw InputError(what + ": " + std::to_string(lo) + "," + std::to_string(hi) +
                         " is not a colour range LO,HI with 0 < LO < HI <= 1");
}

ColourRange parseColourRange(const std::string& text, const std::string& flag) {
    const size_t comma = text.find(',');
    ColourRange range{0, 0};
    if (comma == std::string::npos ||
        !parseNumber(trim(std::string_view(text).substr(0, comma)), &range.lo) ||
        !parseNumber(trim(std::string_view(text).substr(comma + 1)), &range.hi))
        throw InputError(flag + ": expected LO,HI with 0 < LO < HI <= 1, got \"" +
                         printable(text) + "\"");
    range.validate(flag);
    return range;
}

double ColourRange::sOf(double cTT) const { return -std::log(std::clamp(cTT, lo, hi)); }

ColourBasis::ColourBasis(ColourRange range, std::vector<std::vector<double>> table,
                         const std::string& source)
    : range_(range), table_(std::move(table)) {
    range_.validate(source + ": range");
    const int k = functions();
    if (k < 1 || k > kMaxFunctions)
        throw InputError(source + ": " + std::to_string(k) + " functions (allowed: 1.." +
                         std::to_string(kMaxFunctions) + ")");
    const size_t g = table_[0].size();
    if (g < 2 || g > 1024)
        throw InputError(source + ": " + std::to_string(g) + " nodes (allowed: 2..1024)");
    for (int j = 0; j < k; ++j) {
        if (table_[j].size() != g)
            throw InputError(source + ": function " + std::to_string(j) + " has " +
                             std::to_string(table_[j].size()) + " values, function 0 has " +
                             std::to_string(g));
        for (double v : table_[j])
            if (!std::isfinite(v) || std::abs(v) > 1e6 || (j == 0 && v != 1.0))
                throw InputError(
                    source + ": function " + std::to_string(j) + " has the value " +
                    std::to_string(v) +
                    (j == 0 ? " (function 0 is the constant 1)" : " (must be finite, |v| <= 1e6)"));
    }
    sLo_ = -std::log(range_.hi);
    sStep_ = (-std::log(range_.lo) - sLo_) / static_cast<double>(g - 1);
}

double ColourBasis::nodeS(int g) const { return sLo_ + sStep_ * g; }

void ColourBasis::eval(double cTT, double* phi) const {
    const double t = (range_.sOf(cTT) - sLo_) / sStep_;
    const int last = nodes() - 1;
    const int g = std::clamp(static_cast<int>(t), 0, last - 1);
    const double f = std::clamp(t - g, 0.0, 1.0);
    for (int j = 0; j < functions(); ++j)
        phi[j] = table_[j][g] + f * (table_[j][g + 1] - table_[j][g]);
}

nlohmann::json ColourBasis::toJson() const {
    return {{"c_tt_range", {range_.lo, range_.hi}},
            {"variable", "s = -ln(C_TT), nodes uniform in s from -ln(hi) to -ln(lo)"},
            {"functions", table_}};
}

ColourBasis ColourBasis::fromJson(const nlohmann::json& j, const std::string& source) {
    const JsonObjectReader r(j, source);
    const std::vector<double> range =
        r.numbers("c_tt_range", 2, NumberRange::openClosed(0, 1), "(lo, hi)");
    const nlohmann::json& f = r.value("functions");
    if (!f.is_array() || f.empty() || f.size() > kMaxFunctions)
        throw InputError(source + ": \"functions\" must be an array of 1.." +
                         std::to_string(kMaxFunctions) + " arrays of numbers");
    std::vector<std::vector<double>> table;
    for (const auto& row : f) {
        if (!row.is_array()) throw InputError(source + ": \"functions\" holds a non-array");
        std::vector<double> values;
        for (const auto& v : row) {
            if (!v.is_number()) throw InputError(source + ": \"functions\" holds a non-number");
            values.push_back(v.get<double>());
        }
        table.push_back(std::move(values));
    }
    return ColourBasis({range[0], range[1]}, std::move(table), source);
}

NetworkWeights foldColourIntoNetwork(const NetworkWeights& conditioned, const ColourBasis& basis,
                                     const Rgb& colour) {
    const int functions = basis.functions();
    if (conditioned.layers.empty() || conditioned.outputs() != 3 * functions ||
        conditioned.output != OutputFunction::Identity)
        throw std::logic_error("foldColourIntoNetwork: not a conditioned network of the basis");
    NetworkWeights folded = conditioned;
    const NetworkLayer& last = conditioned.layers.back();
    NetworkLayer& out = folded.layers.back();
    out.out = 3;
    out.weight.assign(static_cast<size_t>(3) * last.in, 0.0f);
    out.bias.assign(3, 0.0f);
    double phi[ColourBasis::kMaxFunctions];
    for (int c = 0; c < 3; ++c) {
        basis.eval(colour[c], phi);
        for (int i = 0; i < last.in; ++i) {
            double w = 0;
            for (int j = 0; j < functions; ++j) w += phi[j] * last.w(3 * j + c, i);
            out.weight[static_cast<size_t>(c) * last.in + i] = static_cast<float>(w);
        }
        double b = 0;
        for (int j = 0; j < functions; ++j) b += phi[j] * last.bias[3 * j + c];
        out.bias[c] = static_cast<float>(b);
    }
    folded.output = OutputFunction::Exp;
    return folded;
}

Rgb conditionedM(const float* coefficients, const ColourBasis& basis, const Rgb& colour) {
    double phi[ColourBasis::kMaxFunctions];
    Rgb m;
    for (int c = 0; c < 3; ++c) {
        basis.eval(colour[c], phi);
        double z = 0;
        for (int j = 0; j < basis.functions(); ++j) z += coefficients[3 * j + c] * phi[j];
        m[c] = std::exp(z);
    }
    return m;
}

}  // namespace weft
