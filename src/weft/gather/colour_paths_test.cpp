// Any-colour gathers: the recoloured RDM against ordinary gathers of that
// colour (independent walks, batch-means z-test), exact reproduction of the
// gathered colour, determinism, shards, and damaged records.
#include "weft/gather/colour_paths.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/text_parse.h"
#include "weft/core/file.h"
#include "weft/core/npy.h"
#include "weft/core/test_util.h"
#include "weft/fiber/fiber_test_util.h"
#include "weft/gather/gather_merge.h"

namespace weft {
namespace {

GatherOptions anyColourOptions() {
    GatherOptions o;
    // Gabardine: chromatic C_R (W0 differs per channel) and a near-white red C_TT.
    o.fiber = testing::table3Fiber("gabardine");
    o.ply = {60, 0.3, 0.12};
    o.paths = testing::scaled(40000);
    o.seed = 21;
    o.plySeed = 4;  // one ply for every gather of a test: the RDM is that ply's
    o.bins = {2, 4, 4, 8};
    o.maxDepth = 8;  // some paths are truncated, so their records are exercised
    o.anyColour = true;
    o.quiet = true;
    return o;
}

// Per-shard estimates of coarse cells: (kind, incident bin, theta_o row or 0
// for truncated, channel) -> weight per path of that incident bin.
using CoarseCells = std::map<std::array<int, 4>, double>;

CoarseCells coarseFromSums(const GatherSums& s) {
    const RdmBins& b = s.bins;
    const size_t nOut = b.outgoingCount();
    CoarseCells cells;
    for (size_t i = 0; i < b.incidentCount(); ++i) {
        const double n = static_cast<double>(s.count[i]);
        for (int c = 0; c < 3; ++c) {
            cells[{2, static_cast<int>(i), 0, c}] +=
                s.sumTruncated[i * 3 + c] / GatherSums::kFixedScale / n;
            for (size_t j = 0; j < nOut; ++j) {
                const int row = static_cast<int>(j) / b.phiO;
                const size_t cell = (i * nOut + j) * 3 + c;
                cells[{0, static_cast<int>(i), row, c}] +=
                    s.sumR[cell] / GatherSums::kFixedScale / n;
                cells[{1, static_cast<int>(i), row, c}] +=
                    s.sumM[cell] / GatherSums::kFixedScale / n;
            }
        }
    }
    return cells;
}

// The sums of `s` with its recorded paths' weights for cTT.
GatherSums recolouredInMemory(const GatherSums& s, const Rgb& cTT) {
    GatherSums r = s;
    std::fill(r.sumR.begin(), r.sumR.end(), 0);
    std::fill(r.sumM.begin(), r.sumM.end(), 0);
    std::fill(r.sumTruncated.begin(), r.sumTruncated.end(), 0);
    for (const ColourPath& p : s.colourPaths)
        addColourPath(r, p, cTT, [](int64_t& cell, int64_t v) { cell += v; });
    return r;
}

struct BatchMean {
    double mean = 0, varianceOfMean = 0;
};

std::map<std::array<int, 4>, BatchMean> batchMeans(const std::vector<CoarseCells>& batches) {
    std::map<std::array<int, 4>, BatchMean> out;
    const double n = static_cast<double>(batches.size());
    for (const auto& [key, unused] : batches[0]) {
        double sum = 0, sumSq = 0;
        for (const CoarseCells& b : batches) sum += b.at(key), sumSq += b.at(key) * b.at(key);
        const double mean = sum / n;
        out[key] = {mean, std::max(0.0, sumSq / n - mean * mean) / (n - 1)};
    }
    return out;
}

struct ZTest {
    double maxAbsT = 0, meanTSquared = 0;
    int cells = 0;
};

ZTest compare(const std::map<std::array<int, 4>, BatchMean>& a,
              const std::map<std::array<int, 4>, BatchMean>& b) {
    ZTest z;
    double sumSq = 0;
    for (const auto& [key, x] : a) {
        const BatchMean& y = b.at(key);
        const double variance = x.varianceOfMean + y.varianceOfMean;
        if (variance == 0) {
            EXPECT_EQ(x.mean, y.mean) << "cell kind " << key[0] << " bin " << key[1];
            continue;
        }
        const double t = (x.mean - y.mean) / std::sqrt(variance);
        z.maxAbsT = std::max(z.maxAbsT, std::abs(t));
        sumSq += t * t;
        ++z.cells;
    }
    z.meanTSquared = sumSq / z.cells;
    return z;
}

TEST(AnyColourGather, RecolouredRdmMatchesOrdinaryGathersOfThatColour) {
    // Independent truth: ordinary gathers (colour-dependent lobe choice,
    // mixture weights) with the target C_TT, other walks on the same ply.
    // Each side is 16 shards; their spread gives each cell's standard error.
    const Rgb target(0.35, 0.8, 0.97);
    const int batches = 16;
    GatherOptions anyColour = anyColourOptions();
    GatherOptions ordinary = anyColourOptions();
    ordinary.anyColour = false;
    ordinary.fiber.cTT = target;
    ordinary.seed = 22;
    std::vector<CoarseCells> recoloured, plain, notRecoloured;
    for (int k = 0; k < batches; ++k) {
        anyColour.shard = ordinary.shard = {k, batches};
        const GatherSums s = gatherSums(anyColour);
        ASSERT_FALSE(s.colourPaths.empty());
        recoloured.push_back(coarseFromSums(recolouredInMemory(s, target)));
        notRecoloured.push_back(coarseFromSums(s));
        plain.push_back(coarseFromSums(gatherSums(ordinary)));
    }
    const auto truth = batchMeans(plain);
    const ZTest z = compare(batchMeans(recoloured), truth);
    std::printf("recoloured vs ordinary: %d cells, max |t| %.2f, mean t^2 %.2f\n", z.cells,
                z.maxAbsT, z.meanTSquared);
    EXPECT_GT(z.cells, 100);
    // t with 15 degrees of freedom per side: P(|t| > 5.5) < 1e-4 per cell;
    // E[t^2] = 15 / 13, with a standard error of about 0.13 over ~200 cells.
    EXPECT_LT(z.maxAbsT, 5.5);
    EXPECT_LT(z.meanTSquared, 1.7);
    // The same test rejects the gathered colour: it can fail.
    const ZTest wrong = compare(batchMeans(notRecoloured), truth);
    EXPECT_GT(wrong.maxAbsT, 10.0);
}

TEST(AnyColourGather, IsAnOrdinaryGatherOfItsOwnColourAndDoesNotDependOnThreads) {
    GatherOptions o = anyColourOptions();
    o.threads = 1;
    const GatherResult one = gatherRdm(o);
    o.threads = 2;
    const GatherResult two = gatherRdm(o);
    EXPECT_TRUE(one.colourPaths == two.colourPaths);
    EXPECT_EQ(one.rdmM, two.rdmM);
    // Every interacting path with a weight is recorded; T paths are not.
    const int64_t interacting = o.paths - one.depth[0];
    EXPECT_LE(static_cast<int64_t>(one.colourPaths.size()), interacting);
    EXPECT_GT(static_cast<double>(one.colourPaths.size()), 0.99 * interacting);
    int truncated = 0, r = 0;
    for (const ColourPath& p : one.colourPaths) {
        truncated += p.kind == ColourPath::Truncated;
        r += p.kind == ColourPath::R;
        if (p.kind == ColourPath::R) {
            EXPECT_LE(p.ttEvents, 1);
        }
    }
    EXPECT_EQ(truncated, one.depth[o.maxDepth + 1]);
    EXPECT_GT(r, 0);
    // The gathered colour reproduces the sums exactly.
    const GatherSums again = recolouredInMemory(gatherSums(o), o.fiber.cTT);
    const GatherResult reproduced = normaliseGather(again, o);
    EXPECT_EQ(reproduced.rdmR, one.rdmR);
    EXPECT_EQ(reproduced.rdmM, one.rdmM);
    EXPECT_EQ(reproduced.truncated, one.truncated);
}

TEST(AnyColourGather, RecolouredToWhiteIsAWhiteFurnace) {
    // With C_TT = 1 the fiber's albedo F + (1 - F) C_TT is 1 in every channel
    // whatever C_R (here chromatic): every incident bin's expected energy
    // T + R + M + truncated is 1. Each event's weight (F_c / p_R or
    // (1 - F_c) / (1 - p_R)) is not 1 per channel, so this checks the
    // per-lobe weights and the recolouring against the furnace, per path.
    GatherOptions o = anyColourOptions();
    o.fiber.cR = Rgb(0.5, 0.2, 0.05);
    o.paths = testing::scaled(60000);
    const GatherSums s = gatherSums(o);
    const size_t nIn = o.bins.incidentCount();
    std::vector<std::array<double, 3>> sum(nIn), sumSq(nIn);
    for (const ColourPath& p : s.colourPaths)
        for (int c = 0; c < 3; ++c) {
            const double w = p.weightFor(Rgb(1.0), c);
            sum[p.incidentBin][c] += w;
            sumSq[p.incidentBin][c] += w * w;
        }
    double worst = 0;
    for (size_t i = 0; i < nIn; ++i) {
        const double n = static_cast<double>(s.count[i]), t = static_cast<double>(s.countT[i]);
        for (int c = 0; c < 3; ++c) {
            // T paths weigh 1.
            const double mean = (sum[i][c] + t) / n;
            const double variance = (sumSq[i][c] + t) / n - mean * mean;
            const double z = (mean - 1.0) / std::sqrt(variance / n);
            worst = std::max(worst, std::abs(z));
            EXPECT_LT(std::abs(z), 4.5) << "incident bin " << i << " channel " << c << ": " << mean;
        }
    }
    std::printf("white furnace: largest |z| %.2f over %zu bins x 3 channels\n", worst, nIn);
}

class ColourPathsFileTest : public testing::TempDirTest {
  protected:
    // A gather of `o` with 2000 paths, written to path("g").
    GatherResult writeSmallGather(GatherOptions& o) {
        o.paths = 2000;
        GatherResult g = gatherRdm(o);
        TempDirCommit out(path("g"));
        writeGather(g, o, out);
        return g;
    }
};

TEST_F(ColourPathsFileTest, RecolourOfTheDirectoryReproducesItAndMergesShardsInPathOrder) {
    GatherOptions o = anyColourOptions();
    o.paths = 3000;
    const GatherResult whole = gatherRdm(o);
    {
        TempDirCommit out(path("whole"));
        writeGather(whole, o, out);
    }
    RecolouredGather same = recolourGather(path("whole"), o.fiber.cTT);
    EXPECT_EQ(same.gatheredCTT, o.fiber.cTT);
    EXPECT_FALSE(same.options.anyColour);
    const GatherResult r = normaliseGather(std::move(same.sums), same.options);
    EXPECT_EQ(r.rdmR, whole.rdmR);
    EXPECT_EQ(r.rdmM, whole.rdmM);
    EXPECT_EQ(r.truncated, whole.truncated);
    EXPECT_EQ(r.pT, whole.pT);
    EXPECT_EQ(r.depth, whole.depth);
    EXPECT_DOUBLE_EQ(r.stats.meanDepth, whole.stats.meanDepth);

    // Three shards, given out of order: the merged records are the unsharded ones.
    std::vector<std::string> parts;
    for (int k : {2, 0, 1}) {
        o.shard = {k, 3};
        TempDirCommit out(path("part" + std::to_string(k)));
        writeGatherPart(gatherSums(o), o, out);
        parts.push_back(out.finalPath());
    }
    const MergedGather merged = mergeGatherParts(parts);
    EXPECT_EQ(merged.sums.colourPaths.size(), whole.colourPaths.size());
    EXPECT_TRUE(merged.sums.colourPaths == whole.colourPaths);
}

TEST_F(ColourPathsFileTest, DamagedRecordsAndOrdinaryGathersAreRefused) {
    GatherOptions o = anyColourOptions();
    const GatherResult g = writeSmallGather(o);
    const std::string dir = path("g");
    const auto file = [&](const char* name) {
        return (std::filesystem::path(dir) / name).string();
    };
    const Rgb colour(0.5, 0.5, 0.5);
    const auto rows = g.colourPaths.size();

    // Kind out of range.
    std::vector<uint8_t> kinds(rows, ColourPath::M);
    kinds[5] = 7;
    writeNpy(file("paths_kind.npy"), kinds.data(), {rows});
    testing::expectInputError([&] { recolourGather(dir, colour); },
                              {"paths_kind.npy", "row 5", "kind 7", "0 R, 1 M, 2 truncated"});
    // Fewer rows than the other arrays.
    writeNpy(file("paths_kind.npy"), kinds.data(), {rows - 1});
    testing::expectInputError([&] { recolourGather(dir, colour); }, {"rows (must be equal)"});
    // Restore the kinds, then damage bins and weights.
    for (size_t k = 0; k < rows; ++k) kinds[k] = g.colourPaths[k].kind;
    writeNpy(file("paths_kind.npy"), kinds.data(), {rows});
    std::vector<int32_t> bins;
    std::vector<float> weights;
    for (const ColourPath& p : g.colourPaths) {
        bins.insert(bins.end(), {p.incidentBin, p.outgoingBin, p.ttEvents});
        weights.insert(weights.end(), {p.weight[0], p.weight[1], p.weight[2]});
    }
    std::vector<int32_t> badBins = bins;
    badBins[3 * 9] = 8;  // 2 x 4 incident bins
    writeNpy(file("paths_bins.npy"), badBins.data(), {rows, 3});
    testing::expectInputError([&] { recolourGather(dir, colour); },
                              {"paths_bins.npy", "row 9", "incident bin 8", "0..7"});
    badBins = bins;
    badBins[3 * 4 + 2] = -1;
    writeNpy(file("paths_bins.npy"), badBins.data(), {rows, 3});
    testing::expectInputError([&] { recolourGather(dir, colour); }, {"row 4", "TT events -1"});
    writeNpy(file("paths_bins.npy"), bins.data(), {rows, 3});
    std::vector<float> badWeights = weights;
    badWeights[3 * 11 + 1] = std::nanf("");
    writeNpy(file("paths_weight.npy"), badWeights.data(), {rows, 3});
    testing::expectInputError([&] { recolourGather(dir, colour); },
                              {"paths_weight.npy", "row 11", "weight nan in channel 1",
                               "finite, >= 0 and < 2^31"});
    writeNpy(file("paths_weight.npy"), weights.data(), {rows, 3});
    std::filesystem::remove(file("paths_bins.npy"));
    testing::expectInputError([&] { recolourGather(dir, colour); }, {"paths_bins.npy"});
    writeNpy(file("paths_bins.npy"), bins.data(), {rows, 3});
    EXPECT_NO_THROW(recolourGather(dir, colour));

    // An ordinary gather has no records to recolour.
    o.anyColour = false;
    {
        TempDirCommit out(path("plain"));
        writeGather(gatherRdm(o), o, out);
    }
    EXPECT_FALSE(std::filesystem::exists(path("plain") + "/paths_bins.npy"));
    testing::expectInputError([&] { recolourGather(path("plain"), colour); },
                              {"meta.json", "not an any-colour gather", "--any-colour"});
}

// Issue 41, item 3: a record of W0 = 3e38 gave rdm_m.npy values of
// -13,664,891: its fixed-point weight overflowed int64. Records whose sums
// the accumulators cannot hold are refused where they are read (recolour,
// merge, the colour fit, Python); those they can hold are recoloured.
TEST_F(ColourPathsFileTest, WeightsTheFixedPointSumsCannotHoldAreRefused) {
    GatherOptions o = anyColourOptions();
    const GatherResult g = writeSmallGather(o);
    const std::string dir = path("g");
    const std::string weightPath = dir + "/paths_weight.npy";
    const ColourPathColumns columns = colourPathColumns(g.colourPaths);
    const size_t rows = g.colourPaths.size();
    const Rgb colour(0.5, 0.5, 0.5);
    std::vector<float> w = columns.weights;
    for (const float huge : {3e38f, kMaxRecordWeight, std::numeric_limits<float>::infinity()}) {
        w[3 * 7 + 1] = huge;
        writeNpy(weightPath, w.data(), {rows, 3});
        testing::expectInputError([&] { recolourGather(dir, colour); },
                                  {weightPath, "row 7", "channel 1", "< 2^31"});
        testing::expectInputError([&] { loadColourPaths(dir); }, {weightPath, "row 7"});
    }
    // The largest weight one record may hold: recoloured, positive and finite.
    w[3 * 7 + 1] = std::nextafter(kMaxRecordWeight, 0.0f);
    writeNpy(weightPath, w.data(), {rows, 3});
    {
        RecolouredGather r = recolourGather(dir, Rgb(1.0));
        const ColourPath& p = g.colourPaths[7];
        const GatherResult n = normaliseGather(std::move(r.sums), r.options);
        const std::vector<float>& map = p.kind == ColourPath::R ? n.rdmR : n.rdmM;
        if (p.kind != ColourPath::Truncated) {
            const float v = map[(p.incidentBin * o.bins.outgoingCount() + p.outgoingBin) * 3 + 1];
            EXPECT_TRUE(std::isfinite(v) && v > 1e3f) << v;
        }
    }
    // Three records of one cell, each within the limit, whose sum is not.
    w = columns.weights;
    std::vector<int32_t> bins = columns.bins;
    std::vector<size_t> same;
    for (size_t k = 0; k < rows && same.size() < 3; ++k)
        if (g.colourPaths[k].kind == ColourPath::M &&
            g.colourPaths[k].incidentBin == g.colourPaths[0].incidentBin)
            same.push_back(k);
    ASSERT_EQ(same.size(), 3u);
    for (size_t k : same) {
        bins[3 * k + 1] = g.colourPaths[same[0]].outgoingBin;
        w[3 * k] = 1073741824.0f;  // 2^30
    }
    writeNpy(weightPath, w.data(), {rows, 3});
    writeNpy(dir + "/paths_bins.npy", bins.data(), {rows, 3});
    testing::expectInputError([&] { recolourGather(dir, colour); },
                              {weightPath, "row " + std::to_string(same[1]), "channel 0",
                               "summed M weight of incident bin", "fixed-point sums"});
    writeNpy(weightPath, columns.weights.data(), {rows, 3});
    writeNpy(dir + "/paths_bins.npy", columns.bins.data(), {rows, 3});
    EXPECT_NO_THROW(recolourGather(dir, colour));
}

TEST_F(ColourPathsFileTest, MoreRecordsThanPathsOfTheirBinAreRefused) {
    GatherOptions o = anyColourOptions();
    const GatherResult g = writeSmallGather(o);
    const std::string dir = path("g");
    // The incident bin with the fewest paths that met a fiber gets one record more.
    size_t fewest = 0;
    for (size_t i = 0; i < g.count.size(); ++i)
        if (g.count[i] - g.countT[i] < g.count[fewest] - g.countT[fewest]) fewest = i;
    const int64_t interacting = g.count[fewest] - g.countT[fewest];
    const size_t rows = g.colourPaths.size();
    ASSERT_LT(interacting + 1, static_cast<int64_t>(rows));
    std::vector<int32_t> bins = colourPathColumns(g.colourPaths).bins;
    for (int64_t k = 0; k <= interacting; ++k) bins[3 * k] = static_cast<int32_t>(fewest);
    writeNpy(dir + "/paths_bins.npy", bins.data(), {rows, 3});
    testing::expectInputError([&] { recolourGather(dir, Rgb(0.5)); },
                              {dir + "/paths_bins.npy", "row " + std::to_string(interacting),
                               "incident bin " + std::to_string(fewest), "met a fiber"});
}

TEST(ParseColour, AcceptsThreeValuesInTheUnitIntervalOnly) {
    EXPECT_EQ(parseColour("0.5,0,1", "--c-tt"), Rgb(0.5, 0.0, 1.0));
    EXPECT_EQ(parseColour(" 0.25 , 0.5 ,0.75", "--c-tt"), Rgb(0.25, 0.5, 0.75));
    for (const char* bad : {"", "0.5", "0.5,0.5", "0.5,0.5,0.5,0.5", "1.5,0,0", "-0.1,0,0",
                            "nan,0,0", "a,b,c", "0.5,,0.5"})
        testing::expectInputError([&] { parseColour(bad, "--c-tt"); },
                                  {"--c-tt", "R,G,B", "[0, 1]"});
}

}  // namespace
}  // namespace weft
