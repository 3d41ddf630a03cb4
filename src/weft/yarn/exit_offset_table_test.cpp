// The model's exit-offset density (yarn/exit_offset_table.h): merged bins
// keep their mass, the density integrates to 1, samples follow it (Pearson
// chi-square), cells without M light have none, the file form reads back
// bit for bit, bad input is refused.
#include "weft/yarn/exit_offset_table.h"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "weft/core/chi2.h"
#include "weft/core/error.h"
#include "weft/core/math.h"
#include "weft/core/rng.h"
#include "weft/core/test_util.h"

namespace weft {
namespace {

using Histogram = std::vector<double>;

double& weightAt(Histogram& h, size_t cell, size_t slot, int c) {
    return h[(cell * kExitOffsetSlots + slot) * 3 + c];
}

// A gather-like histogram: cell 5, channel 1 a heavy-tailed blob around
// (0.3, -0.5), correlated; cell 5, channel 0 one fine slot; some mass beyond
// the axial range; every other cell and channel empty.
Histogram testHistogram() {
    Histogram h(kExitOffsetCells * kExitOffsetSlots * 3, 0.0);
    for (int i = 0; i < kExitOffsetAxialBins; ++i)
        for (int j = 0; j < kExitOffsetAroundBins; ++j) {
            const double z = (i + 0.5 - 0.5 * kExitOffsetAxialBins) * kExitOffsetAxialWidth;
            const double p = -kPi + (j + 0.5) * kTwoPi / kExitOffsetAroundBins;
            const double r = std::hypot(z - 0.3 - 0.4 * (p + 0.5), p + 0.5);
            weightAt(h, 5, static_cast<size_t>(i) * kExitOffsetAroundBins + j, 1) =
                1.0 / (1.0 + 4 * r * r * r);
        }
    weightAt(h, 5, kExitOffsetSlots - 1, 1) = 3.0;  // beyond: left out
    weightAt(h, 5, 70 * kExitOffsetAroundBins + 9, 0) = 0.25;
    return h;
}

// Edges of every merged bin, in the table's own units.
ExitOffsetTable::Edges testEdges() {
    return {{-8, -2, -1, -0.5, 0, 0.25, 0.75, 1.5, 4, 8}, {-1, -0.5, -0.25, 0, 0.125, 0.5, 1}};
}

// The fine histogram's weight of cell 5, channel 1 in [z0, z1) x [p0, p1) pi.
double fineWeight(const Histogram& h, double z0, double z1, double p0, double p1) {
    double sum = 0;
    for (int i = 0; i < kExitOffsetAxialBins; ++i)
        for (int j = 0; j < kExitOffsetAroundBins; ++j) {
            const double z = (i + 0.5 - 0.5 * kExitOffsetAxialBins) * kExitOffsetAxialWidth;
            const double p = -1 + (j + 0.5) * 2.0 / kExitOffsetAroundBins;
            if (z >= z0 && z < z1 && p >= p0 && p < p1)
                sum +=
                    h[(5 * kExitOffsetSlots + static_cast<size_t>(i) * kExitOffsetAroundBins + j) *
                          3 +
                      1];
        }
    return sum;
}

TEST(ExitOffsetTable, MergedBinsKeepTheirMassAndTheDensityIntegratesToOne) {
    Histogram h = testHistogram();
    const ExitOffsetTable::Edges edges = testEdges();
    const ExitOffsetTable t = ExitOffsetTable::fromHistogram(h, edges, "test");
    EXPECT_EQ(t.axialBins(), 9);
    EXPECT_EQ(t.aroundBins(), 6);
    EXPECT_TRUE(t.hasDensity(5, 1));
    EXPECT_TRUE(t.hasDensity(5, 0));
    EXPECT_FALSE(t.hasDensity(5, 2));
    EXPECT_FALSE(t.hasDensity(4, 1));
    // Channel 0's one fine slot (row 70: dz in [0.75, 0.875), column 9: dpsi
    // in [-0.71875, -0.6875) pi) falls in bin (6, 0): all of it, as a density
    // over that bin's area.
    const double area = (1.5 - 0.75) * (0.5 * kPi);
    EXPECT_NEAR(t.pdf(5, 0, 0.8, -0.7 * kPi) * area, 1.0, 1e-12);
    EXPECT_NEAR(t.pdf(5, 0, 1.4, -0.55 * kPi) * area, 1.0, 1e-12);
    EXPECT_EQ(t.pdf(5, 0, 1.6, -0.7 * kPi), 0.0);
    EXPECT_EQ(t.pdf(5, 0, 0.8, -0.45 * kPi), 0.0);
    // Each merged bin's probability is its fine bins' share of the weight
    // within the range (to the masses' rounding), and the density's
    // integral, bin by bin, is 1.
    const double inRange = fineWeight(h, -8, 8, -1, 1);
    double integral = 0;
    for (int i = 0; i < t.axialBins(); ++i)
        for (int j = 0; j < t.aroundBins(); ++j) {
            const double z0 = edges.dz[i], z1 = edges.dz[i + 1];
            const double p0 = edges.dpsiPi[j], p1 = edges.dpsiPi[j + 1];
            const double probability =
                t.pdf(5, 1, 0.5 * (z0 + z1), 0.5 * (p0 + p1) * kPi) * (z1 - z0) * (p1 - p0) * kPi;
            EXPECT_NEAR(probability, t.probability(5, 1, i, j), 1e-12);
            ASSERT_NEAR(probability, fineWeight(h, z0, z1, p0, p1) / inRange, 2e-6)
                << i << " " << j;
            integral += probability;
        }
    EXPECT_NEAR(integral, 1.0, 1e-4);
    // Outside the range, or a cell without density: 0; its sample: no offset.
    EXPECT_EQ(t.pdf(5, 1, 8.0, 0.0), 0.0);
    EXPECT_EQ(t.pdf(5, 1, -8.01, 0.0), 0.0);
    EXPECT_EQ(t.pdf(4, 1, 0.1, 0.1), 0.0);
    const ExitOffsetTable::Offset none = t.sample(4, 1, 0.3, 0.7);
    EXPECT_EQ(none.dz, 0.0);
    EXPECT_EQ(none.dpsi, 0.0);
    EXPECT_EQ(none.pdf, 0.0);
    // A narrower axial range leaves the rest out: the mass within it renormalised.
    const ExitOffsetTable narrow = ExitOffsetTable::fromHistogram(h, {{-1, 1}, {-1, 1}}, "test");
    EXPECT_NEAR(narrow.pdf(5, 1, 0.0, 0.0) * 2 * kTwoPi, 1.0, 1e-6);
}

TEST(ExitOffsetTable, DefaultEdgesAreSymmetricAndOnTheGathersGrid) {
    const ExitOffsetTable::Edges e = ExitOffsetTable::defaultEdges();
    ASSERT_EQ(e.dz.size(), 23u);
    ASSERT_EQ(e.dpsiPi.size(), 15u);
    for (size_t k = 0; k < e.dz.size(); ++k) EXPECT_EQ(e.dz[k], -e.dz[e.dz.size() - 1 - k]);
    for (size_t k = 0; k < e.dpsiPi.size(); ++k)
        EXPECT_EQ(e.dpsiPi[k], -e.dpsiPi[e.dpsiPi.size() - 1 - k]);
    EXPECT_EQ(e.dz.front(), -0.5 * kExitOffsetAxialBins * kExitOffsetAxialWidth);
    const ExitOffsetTable t = ExitOffsetTable::fromHistogram(testHistogram(), e, "test");
    EXPECT_EQ(t.axialBins(), 22);
    EXPECT_EQ(t.aroundBins(), 14);
}

TEST(ExitOffsetTable, SamplesFollowThePdf) {
    const ExitOffsetTable t = ExitOffsetTable::fromHistogram(testHistogram(), testEdges(), "test");
    const ExitOffsetTable::Edges& e = t.edges();
    const int nz = t.axialBins(), np = t.aroundBins();
    const int samples = testing::scaled(400000);
    std::vector<double> observed(static_cast<size_t>(nz) * np, 0.0), expected(observed.size());
    Rng rng(3, 5);
    double sumDz = 0, expectedDz = 0;
    for (int k = 0; k < samples; ++k) {
        const ExitOffsetTable::Offset o = t.sample(5, 1, rng.uniform(), rng.uniform());
        ASSERT_GT(o.pdf, 0.0);
        ASSERT_EQ(o.pdf, t.pdf(5, 1, o.dz, o.dpsi)) << o.dz << " " << o.dpsi;
        // The sample's bin gives every channel's density there (sampleOffset's MIS).
        for (int c = 0; c < 3; ++c)
            ASSERT_EQ(t.binDensity(5, c, o.axialBin, o.aroundBin), t.pdf(5, c, o.dz, o.dpsi))
                << c << " " << o.dz << " " << o.dpsi;
        const int i =
            static_cast<int>(std::upper_bound(e.dz.begin(), e.dz.end(), o.dz) - e.dz.begin()) - 1;
        const int j =
            static_cast<int>(std::upper_bound(e.dpsiPi.begin(), e.dpsiPi.end(), o.dpsi / kPi) -
                             e.dpsiPi.begin()) -
            1;
        ASSERT_TRUE(i >= 0 && i < nz && j >= 0 && j < np) << o.dz << " " << o.dpsi;
        observed[static_cast<size_t>(i) * np + j] += 1;
        sumDz += o.dz;
    }
    for (int i = 0; i < nz; ++i)
        for (int j = 0; j < np; ++j) {
            const double p = t.probability(5, 1, i, j);
            expected[static_cast<size_t>(i) * np + j] = samples * p;
            expectedDz += p * 0.5 * (e.dz[i] + e.dz[i + 1]);  // uniform within a bin
        }
    const Chi2Result r = chi2Test(observed, expected);
    EXPECT_GT(r.pValue, 0.01) << "chi2 " << r.statistic << " dof " << r.dof;
    EXPECT_NEAR(sumDz / samples, expectedDz, 4 * 3.0 / std::sqrt(samples));
}

TEST(ExitOffsetTable, FileFormReadsBackBitForBit) {
    const ExitOffsetTable t =
        ExitOffsetTable::fromHistogram(testHistogram(), ExitOffsetTable::defaultEdges(), "t");
    const nlohmann::json j = nlohmann::json::parse(t.toJson().dump());
    const ExitOffsetTable back = ExitOffsetTable::fromJson(j, "model.json", "exit_offset");
    EXPECT_EQ(back.toJson(), t.toJson());
    Rng rng(7, 1);
    for (int k = 0; k < 1000; ++k) {
        const double u1 = rng.uniform(), u2 = rng.uniform();
        const ExitOffsetTable::Offset a = t.sample(5, 1, u1, u2), b = back.sample(5, 1, u1, u2);
        ASSERT_EQ(a.dz, b.dz);
        ASSERT_EQ(a.dpsi, b.dpsi);
        ASSERT_EQ(a.pdf, b.pdf);
    }
    EXPECT_EQ(j.at("masses").size(), kExitOffsetCells);
    EXPECT_EQ(j.at("masses")[5][1].size(), 22u * 14u);
}

TEST(ExitOffsetTable, RefusesBadHistogramsEdgesAndFiles) {
    Histogram h = testHistogram();
    testing::expectInputError(
        [&] {
            ExitOffsetTable::fromHistogram(h, {{-8, 0.1, 8}, {-1, 1}}, "gather exit_offset");
        },
        {"gather exit_offset", "dz edges [-8, 0.1, 8]", "multiples of 0.125"});
    testing::expectInputError(
        [&] {
            ExitOffsetTable::fromHistogram(h, {{-8, 9}, {-1, 1}}, "x");
        },
        {"[-8, 8]"});
    testing::expectInputError(
        [&] {
            ExitOffsetTable::fromHistogram(h, {{-1, 1}, {-0.5, 1}}, "x");
        },
        {"dpsi edges [-0.5, 1]", "-1 to 1"});
    testing::expectInputError(
        [&] {
            ExitOffsetTable::fromHistogram(h, {{1, -1}, {-1, 1}}, "x");
        },
        {"increasing"});
    weightAt(h, 2, 17, 1) = -1;
    testing::expectInputError([&] { ExitOffsetTable::fromHistogram(h, testEdges(), "x"); },
                              {"cell 2, slot 17, channel 1", "-1", ">= 0"});
    weightAt(h, 2, 17, 1) = std::nan("");
    testing::expectInputError([&] { ExitOffsetTable::fromHistogram(h, testEdges(), "x"); },
                              {"cell 2, slot 17", "finite"});
    testing::expectInputError(
        [&] {
            ExitOffsetTable::fromHistogram({1.0, 2.0}, testEdges(), "x");
        },
        {"2 numbers", "expected"});

    const nlohmann::json good =
        ExitOffsetTable::fromHistogram(testHistogram(), testEdges(), "t").toJson();
    const auto refused = [&](auto change, const std::vector<std::string>& words) {
        nlohmann::json j = good;
        change(j);
        try {
            ExitOffsetTable::fromJson(j, "m.json", "exit_offset");
            ADD_FAILURE() << "expected an InputError for " << words.front();
        } catch (const InputError& e) {
            const std::string message = e.what();
            EXPECT_NE(message.find("m.json"), std::string::npos) << message;
            for (const std::string& w : words)
                EXPECT_NE(message.find(w), std::string::npos) << message << " lacks " << w;
        }
    };
    refused([](nlohmann::json& j) { j["incident"]["phi_bands"] = 16; },
            {"exit_offset.incident.phi_bands", "16"});
    refused([](nlohmann::json& j) { j["dz_edges"][3] = -3; }, {"exit_offset.dz_edges", "increase"});
    refused([](nlohmann::json& j) { j["dpsi_edges_pi"][6] = 0.75; },
            {"exit_offset.dpsi_edges_pi", "-1 to 1"});
    refused([](nlohmann::json& j) { j["masses"][31][2].erase(0); },
            {"exit_offset.masses[31][2]", "54 integers"});
    refused([](nlohmann::json& j) { j["masses"][3][0][7] = -2; },
            {"exit_offset.masses[3][0][7]", "integer in [0, 4294967295]"});
    refused([](nlohmann::json& j) { j["masses"][3][0][7] = 0.5; }, {"exit_offset.masses[3][0][7]"});
    refused([](nlohmann::json& j) { j["masses"][3][0] = std::vector<uint32_t>(54, 100000000u); },
            {"exit_offset.masses[3][0]", "sum to 5400000000"});
    refused([](nlohmann::json& j) { j["extra"] = 1; }, {"unknown key \"extra\""});
}

}  // namespace
}  // namespace weft
