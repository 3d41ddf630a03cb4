#include "weft/yarn/yarn_appearance.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "weft/core/error.h"
#include "weft/core/image.h"
#include "weft/core/json_message.h"
#include "weft/core/math.h"
#include "weft/core/quadrature.h"
#include "weft/yarn/yarn_integrals.h"

namespace weft {

namespace {

// Incident directions: 4-point Gauss-Legendre panels in theta (3 per
// refinement over [0, pi/2]) times uniform azimuths (16 per refinement), each
// weighted by sin(theta) cos(theta) dtheta dphi (the cosine of the formula
// and the solid angle).
constexpr int kThetaPanels = 3;
constexpr int kAzimuths = 16;

struct IncidentNode {
    Vec3 wi;
    double weight;
};

std::vector<IncidentNode> incidentRule(int refinement) {
    std::vector<double> edges, theta, thetaWeight;
    quadrature::uniformEdges(0.0, kPi / 2, kThetaPanels * refinement, &edges);
    quadrature::panelRule(edges, &theta, &thetaWeight);
    const int azimuths = kAzimuths * refinement;
    std::vector<IncidentNode> nodes;
    for (size_t i = 0; i < theta.size(); ++i) {
        const double sinT = std::sin(theta[i]), cosT = std::cos(theta[i]);
        for (int k = 0; k < azimuths; ++k) {
            const double phi = kTwoPi * (k + 0.5) / azimuths;
            nodes.push_back({Vec3(sinT * std::cos(phi), sinT * std::sin(phi), cosT),
                             thetaWeight[i] * sinT * cosT * kTwoPi / azimuths});
        }
    }
    return nodes;
}

}  // namespace

Rgb yarnAppearance(const YarnBsdf& bsdf, int refinement) {
    const std::vector<IncidentNode> nodes = incidentRule(refinement);
    std::vector<DirectionalIntegrals> at(nodes.size());
    tbb::parallel_for(size_t(0), nodes.size(), [&](size_t i) {
        at[i] = integrateDirections(bsdf, nodes[i].wi, 1, /*secondMoments=*/false);
    });
    // Summed in node order: the same bits at any thread count.
    Rgb scattered;
    double met = 0;
    for (size_t i = 0; i < nodes.size(); ++i) {
        scattered += (at[i].r + at[i].m) * nodes[i].weight;
        met += (1 - at[i].pT) * nodes[i].weight;
    }
    return met > 0 ? scattered / met : Rgb(0.0);
}

AppearanceTable computeAppearanceTable(const YarnModel& conditioned, const std::string& source,
                                       int nodes, double* largestAdjustment) {
    if (!conditioned.colour)
        throw InputError(source +
                         ": an appearance table needs a colour model (weft fit --colour-range)");
    checkRange(source + ": appearance nodes", nodes, 2, 257);
    const ColourRange& range = conditioned.colour->range();
    const double uHi = std::sqrt(-std::log(range.hi)), uLo = std::sqrt(-std::log(range.lo));
    AppearanceTable table;
    for (int g = 0; g < nodes; ++g) {
        // The ends exactly: a rounding past the range would clamp.
        const double cTT = g == 0           ? range.hi
                           : g == nodes - 1 ? range.lo
                                            : std::exp(-sqr(uHi + (uLo - uHi) * g / (nodes - 1)));
        const YarnModel grey = conditioned.forColour(Rgb(cTT), source);
        const YarnBsdf bsdf(grey, source, YarnBsdfOptions{true, YarnSampling::Cosine});
        table.cTT.push_back(cTT);
        table.appearance.push_back(yarnAppearance(bsdf));
    }
    // Physically a darker fiber never makes a brighter yarn. A fitted model
    // can break that by its own error where the change is smallest (at the
    // dark end, where R, which does not depend on C_TT, dominates): the
    // closest non-increasing sequence in least squares (pool adjacent
    // violators) replaces each channel's, so that the inverse stays unique up
    // to a plateau.
    double adjusted = 0;
    for (int c = 0; c < 3; ++c) {
        std::vector<double> value, weight;
        std::vector<int> count;
        for (const Rgb& a : table.appearance) {
            value.push_back(a[c]), weight.push_back(1), count.push_back(1);
            while (value.size() > 1 && value[value.size() - 2] < value.back()) {
                const size_t k = value.size() - 2;
                value[k] = (value[k] * weight[k] + value.back() * weight.back()) /
                           (weight[k] + weight.back());
                weight[k] += weight.back(), count[k] += count.back();
                value.pop_back(), weight.pop_back(), count.pop_back();
            }
        }
        size_t node = 0;
        for (size_t block = 0; block < value.size(); ++block)
            for (int k = 0; k < count[block]; ++k, ++node) {
                adjusted = std::max(adjusted, std::fabs(table.appearance[node][c] - value[block]));
                table.appearance[node][c] = value[block];
            }
    }
    if (largestAdjustment) *largestAdjustment = adjusted;
    table.validate(source + ": its appearance");
    return table;
}

nlohmann::json appearanceReport(const YarnModel& model, const std::string& source,
                                const std::optional<Rgb>& srgbAppearance,
                                const std::optional<Rgb>& cTT, const std::string& appearanceField,
                                const std::string& cTTField) {
    if (srgbAppearance && cTT)
        throw InputError(appearanceField + " and " + cTTField + ": give one of them, not both");
    if (!model.colour)
        throw InputError(source +
                         ": fitted for one colour; an appearance needs a colour model "
                         "(models/MATERIAL-colour.json, or weft fit --colour-range)");
    const AppearanceTable table =
        model.appearance ? *model.appearance : computeAppearanceTable(model, source);
    const ColourRange& range = model.colour->range();
    Rgb darkest, brightest;
    for (int c = 0; c < 3; ++c) darkest[c] = table.darkest(c), brightest[c] = table.brightest(c);
    nlohmann::json report = {
        {"model", source},
        {"c_tt_range", {range.lo, range.hi}},
        {"table", model.appearance ? "stored" : "computed"},
        {"darkest", {{"linear", rgbJson(darkest)}, {"srgb", rgbJson(linearToSrgb(darkest))}}},
        {"brightest",
         {{"linear", rgbJson(brightest)}, {"srgb", rgbJson(linearToSrgb(brightest))}}}};
    if (!srgbAppearance && !cTT) return report;
    Rgb fiber;
    if (srgbAppearance) {
        const Rgb linear = srgbToLinear(*srgbAppearance);
        fiber = table.cTTFor(linear, appearanceField);
        report["appearance"] = {{"srgb", rgbJson(*srgbAppearance)}, {"linear", rgbJson(linear)}};
    } else {
        fiber = *cTT;
    }
    // forColour refuses a C_TT outside the colour range.
    const YarnModel one = model.forColour(fiber, srgbAppearance ? appearanceField : cTTField);
    if (cTT) {
        const Rgb linear = table.appearanceAt(fiber);
        report["appearance"] = {{"srgb", rgbJson(linearToSrgb(linear))},
                                {"linear", rgbJson(linear)}};
    }
    report["c_tt"] = rgbJson(fiber);
    const YarnBsdf bsdf(one, source, YarnBsdfOptions{true, YarnSampling::Cosine});
    report["appearance_direct"] = rgbJson(yarnAppearance(bsdf));
    return report;
}

}  // namespace weft
