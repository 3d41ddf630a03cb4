#include "weft/gather/family.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <set>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/test_util.h"
#include "weft/gather/colour_paths.h"
#include "weft/gather/rdm_io.h"

namespace weft {
namespace {

using testing::expectInputError;

// Polyester (paper Table 3), whose C_R is grey: a zero-width box holds it.
const YarnPoint kPolyester{200, 0.40, 0.20, 5.238, 20.000, 25.000, Rgb(0.7, 0.7, 0.7)};

class FamilyGatherTest : public testing::TempDirTest {
  protected:
    // A zero-width box at polyester (its C_R is grey: one range holds it).
    static FamilyGatherOptions polyesterFamily(int points) {
        const YarnPoint& p = kPolyester;
        FamilyGatherOptions o;
        const auto at = [](double v) { return ParameterRange{v, v}; };
        o.box.fibers = at(p.fibers);
        o.box.density = at(p.density);
        o.box.twist = at(p.twist);
        o.box.betaRDeg = at(p.betaRDeg);
        o.box.betaTTDeg = at(p.betaTTDeg);
        o.box.gammaTTDeg = at(p.gammaTTDeg);
        o.box.cR = at(p.cR.r);
        o.points = points;
        o.pathsPerPoint = 3000;
        o.seed = 5;
        o.bins = {4, 8, 6, 12};
        o.threads = 2;
        o.quiet = true;
        return o;
    }
};

// A zero-width box's point is the preset's yarn, and its folder is exactly
// the ordinary any-colour gather of that yarn with the point's seed.
TEST_F(FamilyGatherTest, ZeroWidthBoxPointIsTheOrdinaryGatherOfThatYarn) {
    const FamilyGatherOptions o = polyesterFamily(2);
    const FamilyGatherSummary s = gatherFamily(o, path("family"));
    EXPECT_EQ(s.pointsGathered, 2);
    const FamilyGather family = loadFamilyGather(path("family"));
    ASSERT_EQ(family.points.size(), 2u);
    EXPECT_EQ(family.points[1], kPolyester);
    GatherOptions ordinary;
    ordinary.fiber = {kPolyester.cR, Rgb(0.5, 0.5, 0.5), 5.238, 20.0, 25.0};
    ordinary.ply = {200, 0.40, 0.20};
    ordinary.paths = 3000;
    ordinary.seed = o.pointOptions(1, family.points[1]).seed;
    ordinary.bins = o.bins;
    ordinary.anyColour = true;
    ordinary.quiet = true;
    {
        TempDirCommit out(path("ordinary"));
        writeGather(gatherRdm(ordinary), ordinary, out);
    }
    for (const char* f : {"count.npy", "count_t.npy", "p_t.npy", "truncated.npy", "depth.npy",
                          "paths_weight.npy", "paths_bins.npy", "paths_kind.npy"})
        EXPECT_EQ(readFile(family.pointDir(1) + "/" + f), readFile(path("ordinary") + "/" + f))
            << f;
    // The point keeps the records only; recoloured to the gathered C_TT they
    // give the ordinary gather's maps, bit for bit.
    EXPECT_FALSE(std::filesystem::exists(family.pointDir(1) + "/rdm_m.npy"));
    EXPECT_FALSE(std::filesystem::exists(family.pointDir(1) + "/ply.txt"));
    expectInputError([&] { loadRdm(family.pointDir(1)); },
                     {"family gather", "weft gather recolour"});
    const auto recoloured = [&](int k) {
        RecolouredGather g = recolourGather(family.pointDir(k), Rgb(0.5, 0.5, 0.5));
        return normaliseGather(std::move(g.sums), g.options);
    };
    const GatherResult a = recoloured(1);
    const RdmData b = loadRdm(path("ordinary"));
    EXPECT_EQ(a.count, b.count);
    EXPECT_EQ(a.pT, b.pT);
    EXPECT_EQ(a.rdmR, b.rdmR);
    EXPECT_EQ(a.rdmM, b.rdmM);
    // The two points are the same yarn with other walks: the same P(T) within noise.
    const GatherResult c = recoloured(0);
    double tA = 0, tC = 0, n = 0;
    for (size_t i = 0; i < a.pT.size(); ++i)
        tA += a.pT[i] * a.count[i], tC += c.pT[i] * c.count[i], n += a.count[i];
    EXPECT_NEAR(tA / n, tC / 3000.0, 4 * std::sqrt(0.25 / 3000));
}

// Shards written into one folder make the family the unsharded run makes;
// a missing shard is named, and a rerun keeps what is there.
TEST_F(FamilyGatherTest, ShardsIntoOneFolderMakeTheWholeFamily) {
    FamilyGatherOptions o = polyesterFamily(3);
    o.box = FamilyBox();  // points over the whole box
    o.pathsPerPoint = 500;
    gatherFamily(o, path("whole"));
    o.shard = Shard::parse("0/2", "--shard");
    EXPECT_EQ(gatherFamily(o, path("sharded")).pointsGathered, 1);
    expectInputError([&] { loadFamilyGather(path("sharded")); }, {"2 of 3 points", "1, 2"});
    o.shard = Shard::parse("1/2", "--shard");
    EXPECT_EQ(gatherFamily(o, path("sharded")).pointsGathered, 2);
    EXPECT_EQ(gatherFamily(o, path("sharded")).pointsKept, 2);
    const FamilyGather whole = loadFamilyGather(path("whole"));
    const FamilyGather sharded = loadFamilyGather(path("sharded"));
    EXPECT_EQ(readFile(path("whole/family.json")), readFile(path("sharded/family.json")));
    std::set<int> fibers;
    for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(readFile(whole.pointDir(k) + "/paths_weight.npy"),
                  readFile(sharded.pointDir(k) + "/paths_weight.npy"));
        fibers.insert(whole.points[k].fibers);
    }
    EXPECT_EQ(fibers.size(), 3u);
}

TEST_F(FamilyGatherTest, RefusesAnotherFamilysFolderAndBadOptions) {
    FamilyGatherOptions o = polyesterFamily(1);
    o.pathsPerPoint = 200;
    gatherFamily(o, path("family"));
    o.seed = 6;
    expectInputError([&] { gatherFamily(o, path("family")); }, {"family.json", "another family"});
    std::filesystem::create_directories(path("other"));
    writeFileAtomic(path("other/notes.txt"), "mine");
    expectInputError([&] { gatherFamily(o, path("other")); }, {"other", "not a family folder"});
    o.points = 0;
    expectInputError([&] { o.validate(); }, {"--points", "[1, 65536]"});
    o.points = 2;
    o.shard = Shard::parse("0/3", "--shard");
    expectInputError([&] { o.validate(); }, {"--shard"});
    // The box's corners must be a ply and a fiber.
    o.shard = Shard();
    o.box.density = {0.2, 1.0};
    expectInputError([&] { o.validate(); }, {"box", "density", "(0, 1)"});
    o.box = FamilyBox();
    o.box.betaRDeg = {0, 8};
    expectInputError([&] { o.validate(); }, {"box", "lower corner", "beta_r_deg"});
    // An edited family.json is refused.
    std::string text = readFile(path("family/family.json"));
    text.replace(text.find("\"fibers\": 200"), 13, "\"fibers\": 201");
    writeFileAtomic(path("family/family.json"), text);
    expectInputError([&] { loadFamilyGather(path("family")); }, {"family.json", "yarns[0]"});
}

}  // namespace
}  // namespace weft
