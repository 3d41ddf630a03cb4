#include "weft/yarn/exit_offset_table.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "weft/core/error.h"
#include "weft/core/json_message.h"
#include "weft/core/json_reader.h"
#include "weft/core/math.h"

namespace weft {

namespace {

std::vector<double> symmetricEdges(const std::vector<double>& positive) {
    std::vector<double> edges;
    for (auto it = positive.rbegin(); it != positive.rend(); ++it)
        if (*it > 0) edges.push_back(-*it);
    edges.insert(edges.end(), positive.begin(), positive.end());
    return edges;
}

// The index of `x` on a grid of step `step` from `origin`, or -1 when it is
// not a grid point within [0, count].
int gridIndex(double x, double origin, double step, int count) {
    const double k = (x - origin) / step;
    const double nearest = std::round(k);
    if (!(std::abs(k - nearest) < 1e-9 && nearest >= 0 && nearest <= count)) return -1;
    return static_cast<int>(nearest);
}

std::string edgeList(const std::vector<double>& edges) {
    std::string s;
    for (double e : edges) s += (s.empty() ? "" : ", ") + formatNumber(e);
    return "[" + s + "]";
}

}  // namespace

ExitOffsetTable::Edges ExitOffsetTable::defaultEdges() {
    return {symmetricEdges({0, 0.125, 0.25, 0.5, 0.75, 1, 1.5, 2, 3, 4, 6, 8}),
            symmetricEdges({0, 1.0 / 16, 1.0 / 8, 1.0 / 4, 3.0 / 8, 1.0 / 2, 3.0 / 4, 1})};
}

ExitOffsetTable ExitOffsetTable::fromHistogram(const std::vector<double>& histogram,
                                               const Edges& edges, const std::string& what) {
    if (histogram.size() != kExitOffsetCells * kExitOffsetSlots * 3)
        throw InputError(what + ": " + std::to_string(histogram.size()) + " numbers, expected " +
                         std::to_string(kExitOffsetCells * kExitOffsetSlots * 3) +
                         " (cells x slots x 3, core/exit_offset.h)");
    // Each edge on the gather's grid: the fine bins between two edges merge.
    const double axialOrigin = -0.5 * kExitOffsetAxialBins * kExitOffsetAxialWidth;
    std::vector<int> dzIndex, psiIndex;
    for (double e : edges.dz)
        dzIndex.push_back(gridIndex(e, axialOrigin, kExitOffsetAxialWidth, kExitOffsetAxialBins));
    for (double e : edges.dpsiPi)
        psiIndex.push_back(gridIndex(e, -1.0, 2.0 / kExitOffsetAroundBins, kExitOffsetAroundBins));
    const auto increasing = [](const std::vector<int>& v) {
        return v.size() >= 2 && std::all_of(v.begin(), v.end(), [](int i) { return i >= 0; }) &&
               std::adjacent_find(v.begin(), v.end(), std::greater_equal<int>()) == v.end();
    };
    if (!increasing(dzIndex))
        throw InputError(what + ": dz edges " + edgeList(edges.dz) +
                         " must be at least 2, increasing, multiples of " +
                         formatNumber(kExitOffsetAxialWidth) + " in [" + formatNumber(axialOrigin) +
                         ", " + formatNumber(-axialOrigin) + "] (the gather's bins)");
    if (!increasing(psiIndex) || psiIndex.front() != 0 || psiIndex.back() != kExitOffsetAroundBins)
        throw InputError(what + ": dpsi edges " + edgeList(edges.dpsiPi) +
                         " (units of pi) must be increasing from -1 to 1, multiples of " +
                         formatNumber(2.0 / kExitOffsetAroundBins) + " (the gather's bins)");

    const size_t nz = dzIndex.size() - 1, np = psiIndex.size() - 1;
    // The merged bin of each fine row and column (-1: outside the edges).
    std::vector<int> rowOf(kExitOffsetAxialBins, -1), columnOf(kExitOffsetAroundBins, -1);
    for (size_t a = 0; a < nz; ++a)
        for (int i = dzIndex[a]; i < dzIndex[a + 1]; ++i) rowOf[i] = static_cast<int>(a);
    for (size_t b = 0; b < np; ++b)
        for (int j = psiIndex[b]; j < psiIndex[b + 1]; ++j) columnOf[j] = static_cast<int>(b);

    std::vector<uint32_t> masses(kExitOffsetCells * 3 * nz * np, 0);
    std::vector<double> merged(nz * np);
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
                    if (rowOf[i] < 0) continue;
                    merged[static_cast<size_t>(rowOf[i]) * np + columnOf[j]] += w;
                    total += w;
                }
            if (!(total > 0)) continue;
            uint32_t* m = &masses[(cell * 3 + c) * nz * np];
            for (size_t k = 0; k < nz * np; ++k)
                m[k] = static_cast<uint32_t>(std::lround(merged[k] / total * kMassScale));
        }
    return fromMasses(edges, masses);
}

ExitOffsetTable ExitOffsetTable::fromMasses(Edges edges, const std::vector<uint32_t>& masses) {
    ExitOffsetTable t;
    t.edges_ = std::move(edges);
    for (double e : t.edges_.dpsiPi) t.dpsiEdges_.push_back(kPi * e);
    const size_t bins = t.bins();
    t.running_.assign(kExitOffsetCells * 3 * (bins + 1), 0);
    for (size_t k = 0; k < kExitOffsetCells * 3; ++k) {
        uint32_t* running = &t.running_[k * (bins + 1)];
        for (size_t b = 0; b < bins; ++b) running[b + 1] = running[b] + masses[k * bins + b];
    }
    return t;
}

nlohmann::json ExitOffsetTable::toJson() const {
    nlohmann::json masses = nlohmann::json::array();
    for (size_t cell = 0; cell < kExitOffsetCells; ++cell) {
        nlohmann::json channels = nlohmann::json::array();
        for (int c = 0; c < 3; ++c) {
            const uint32_t* running = runningOf(cell, c);
            std::vector<uint32_t> m(bins());
            for (size_t b = 0; b < bins(); ++b) m[b] = running[b + 1] - running[b];
            channels.push_back(m);
        }
        masses.push_back(channels);
    }
    return {{"incident", {{"theta_bands", kExitOffsetTheta}, {"phi_bands", kExitOffsetPhi}}},
            {"dz_edges", edges_.dz},
            {"dpsi_edges_pi", edges_.dpsiPi},
            {"masses", masses}};
}

ExitOffsetTable ExitOffsetTable::fromJson(const nlohmann::json& j, const std::string& source,
                                          const std::string& path) {
    if (!j.is_object()) throwJsonError(source, path, "expected an object, got " + describeJson(j));
    JsonObjectReader r(j, source, path);
    r.allowKeys({"incident", "dz_edges", "dpsi_edges_pi", "masses"});
    JsonObjectReader incident = r.object("incident", {"theta_bands", "phi_bands"});
    incident.integer("theta_bands", {kExitOffsetTheta, kExitOffsetTheta, "(core/exit_offset.h)"});
    incident.integer("phi_bands", {kExitOffsetPhi, kExitOffsetPhi, "(core/exit_offset.h)"});
    // Edges: 2 to 1025 finite numbers, strictly increasing; dpsi from -1 to 1.
    const auto readEdges = [&](const char* key, const NumberRange& range) {
        const nlohmann::json& v = r.value(key);
        if (!v.is_array() || v.size() < 2 || v.size() > 1025)
            r.fail(key, "expected an array of 2 to 1025 bin edges, got " + describeJson(v));
        std::vector<double> edges;
        for (size_t k = 0; k < v.size(); ++k) {
            edges.push_back(
                readJsonNumber(v[k], source, r.pathOf(key) + "[" + std::to_string(k) + "]", range));
            if (k > 0 && !(edges[k] > edges[k - 1]))
                r.fail(key, "edges must increase (" + formatNumber(edges[k - 1]) + " then " +
                                formatNumber(edges[k]) + ")");
        }
        return edges;
    };
    Edges edges;
    edges.dz = readEdges("dz_edges", NumberRange::closed(-1024, 1024).with("ply radii"));
    edges.dpsiPi = readEdges("dpsi_edges_pi", NumberRange::closed(-1, 1).with("(units of pi)"));
    if (edges.dpsiPi.front() != -1 || edges.dpsiPi.back() != 1)
        r.fail("dpsi_edges_pi", "must run from -1 to 1 (the whole way round)");

    const size_t bins = (edges.dz.size() - 1) * (edges.dpsiPi.size() - 1);
    const nlohmann::json& m = r.value("masses");
    const std::string shape = "expected " + std::to_string(kExitOffsetCells) +
                              " cells of 3 channels of " + std::to_string(bins) + " integers";
    if (!m.is_array() || m.size() != kExitOffsetCells)
        r.fail("masses", shape + ", got " + describeJson(m));
    std::vector<uint32_t> masses;
    masses.reserve(kExitOffsetCells * 3 * bins);
    for (size_t cell = 0; cell < kExitOffsetCells; ++cell) {
        const std::string cellPath = r.pathOf("masses") + "[" + std::to_string(cell) + "]";
        if (!m[cell].is_array() || m[cell].size() != 3)
            throwJsonError(source, cellPath, shape + ", got " + describeJson(m[cell]));
        for (size_t c = 0; c < 3; ++c) {
            const nlohmann::json& row = m[cell][c];
            const std::string rowPath = cellPath + "[" + std::to_string(c) + "]";
            if (!row.is_array() || row.size() != bins)
                throwJsonError(source, rowPath, shape + ", got " + describeJson(row));
            uint64_t total = 0;
            for (size_t b = 0; b < bins; ++b) {
                const nlohmann::json& v = row[b];
                if (!v.is_number_integer() || v.get<int64_t>() < 0 ||
                    v.get<int64_t>() > std::numeric_limits<uint32_t>::max())
                    throwJsonError(
                        source, rowPath + "[" + std::to_string(b) + "]",
                        "expected an integer in [0, 4294967295], got " + describeJson(v));
                total += v.get<uint64_t>();
                masses.push_back(v.get<uint32_t>());
            }
            if (total > std::numeric_limits<uint32_t>::max())
                throwJsonError(source, rowPath,
                               "masses sum to " + std::to_string(total) +
                                   " (at most 4294967295 per cell and channel)");
        }
    }
    return fromMasses(std::move(edges), masses);
}

bool ExitOffsetTable::hasDensity(size_t cell, int channel) const {
    return !running_.empty() && runningOf(cell, channel)[bins()] > 0;
}

const uint32_t* ExitOffsetTable::runningOf(size_t cell, int channel) const {
    return &running_[(cell * 3 + static_cast<size_t>(channel)) * (bins() + 1)];
}

double ExitOffsetTable::binArea(int axialBin, int aroundBin) const {
    return (edges_.dz[axialBin + 1] - edges_.dz[axialBin]) *
           (dpsiEdges_[aroundBin + 1] - dpsiEdges_[aroundBin]);
}

double ExitOffsetTable::probability(size_t cell, int channel, int axialBin, int aroundBin) const {
    if (!hasDensity(cell, channel)) return 0.0;
    const uint32_t* running = runningOf(cell, channel);
    const size_t k = static_cast<size_t>(axialBin) * aroundBins() + aroundBin;
    return static_cast<double>(running[k + 1] - running[k]) / running[bins()];
}

ExitOffsetTable::Offset ExitOffsetTable::sample(size_t cell, int channel, double u1,
                                                double u2) const {
    Offset o;
    if (!hasDensity(cell, channel)) return o;
    const uint32_t* running = runningOf(cell, channel);
    const size_t n = bins();
    const double target = u1 * running[n];
    // The first bin whose running sum passes the target: it has mass.
    size_t k = static_cast<size_t>(
        std::upper_bound(running + 1, running + n + 1, target,
                         [](double t, uint32_t s) { return t < static_cast<double>(s); }) -
        (running + 1));
    k = std::min(k, n - 1);
    while (k > 0 && running[k + 1] == running[k]) --k;  // u1 rounding onto an empty bin's edge
    const double mass = running[k + 1] - running[k];
    const double f = std::clamp((target - running[k]) / mass, 0.0, 1.0);
    const int i = static_cast<int>(k / aroundBins()), j = static_cast<int>(k % aroundBins());
    o.dz = std::lerp(edges_.dz[i], edges_.dz[i + 1], f);
    o.dpsi = std::lerp(dpsiEdges_[j], dpsiEdges_[j + 1], u2);
    // A bin's upper edge belongs to the next one: keep the sample inside, so
    // that pdf() finds this bin.
    o.dz = std::min(o.dz, std::nextafter(edges_.dz[i + 1], edges_.dz[i]));
    o.dpsi = std::min(o.dpsi, std::nextafter(dpsiEdges_[j + 1], dpsiEdges_[j]));
    o.pdf = mass / running[n] / binArea(i, j);
    o.axialBin = i;
    o.aroundBin = j;
    return o;
}

double ExitOffsetTable::pdf(size_t cell, int channel, double dz, double dpsi) const {
    if (!hasDensity(cell, channel)) return 0.0;
    if (!(dz >= edges_.dz.front() && dz < edges_.dz.back() && dpsi >= dpsiEdges_.front() &&
          dpsi < dpsiEdges_.back()))
        return 0.0;
    const int i = static_cast<int>(std::upper_bound(edges_.dz.begin(), edges_.dz.end(), dz) -
                                   edges_.dz.begin()) -
                  1;
    const int j = static_cast<int>(std::upper_bound(dpsiEdges_.begin(), dpsiEdges_.end(), dpsi) -
                                   dpsiEdges_.begin()) -
                  1;
    return binDensity(cell, channel, i, j);
}

double ExitOffsetTable::binDensity(size_t cell, int channel, int axialBin, int aroundBin) const {
    if (axialBin < 0 || aroundBin < 0) return 0.0;  // a sample without density
    return probability(cell, channel, axialBin, aroundBin) / binArea(axialBin, aroundBin);
}

size_t ExitOffsetTable::memoryBytes() const {
    return running_.size() * sizeof(uint32_t) +
           (edges_.dz.size() + 2 * edges_.dpsiPi.size()) * sizeof(double);
}

}  // namespace weft
