#include "weft/gather/rdm_io.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "weft/core/file.h"
#include "weft/core/npy.h"
#include "weft/core/test_util.h"
#include "weft/fiber/fiber_test_util.h"
#include "weft/gather/gather.h"
#include "weft/gather/rdm_image.h"

namespace weft {
namespace {

class RdmIoTest : public testing::TempDirTest {
protected:
    // A small gather written to DIR/g.
    std::string writeSmallGather(GatherOptions* used = nullptr) {
        GatherOptions o;
        o.fiber = testing::table3Fiber("fleece");
        o.ply = {40, 0.3, 0.2};
        o.paths = 2000;
        o.seed = 3;
        o.bins = {2, 4, 4, 8};
        o.quiet = true;
        result_ = gatherRdm(o);
        TempDirCommit out(path("g"));
        writeGather(result_, o, out);
        if (used) *used = o;
        return path("g");
    }
    GatherResult result_;
};

TEST_F(RdmIoTest, ReadsBackWhatTheGatherWrote) {
    const RdmData d = loadRdm(writeSmallGather());
    EXPECT_EQ(d.bins.toString(), "2,4,4,8");
    EXPECT_EQ(d.count, result_.count);
    EXPECT_EQ(d.pT, result_.pT);
    EXPECT_EQ(d.rdmR, result_.rdmR);
    EXPECT_EQ(d.rdmM, result_.rdmM);
    EXPECT_EQ(d.meta.at("paths").get<int64_t>(), 2000);
}

TEST_F(RdmIoTest, MalformedDirectoriesNameTheFile) {
    const std::string dir = writeSmallGather();
    const std::string meta = readFile(dir + "/meta.json");
    testing::expectInputError([&] { loadRdm(path("missing")); }, {"missing/meta.json"});

    writeFileAtomic(dir + "/meta.json", "{");
    testing::expectInputError([&] { loadRdm(dir); }, {"meta.json", "malformed JSON"});
    auto j = nlohmann::json::parse(meta);
    j["format"] = "something";
    writeFileAtomic(dir + "/meta.json", j.dump());
    testing::expectInputError([&] { loadRdm(dir); }, {"meta.json", "weft-gather"});
    j = nlohmann::json::parse(meta);
    j["version"] = 7;
    writeFileAtomic(dir + "/meta.json", j.dump());
    testing::expectInputError([&] { loadRdm(dir); }, {"unsupported version 7"});
    j = nlohmann::json::parse(meta);
    j["bins"] = {2, 4, 4, 9};  // arrays were written for 2,4,4,8
    writeFileAtomic(dir + "/meta.json", j.dump());
    testing::expectInputError([&] { loadRdm(dir); }, {"rdm_r.npy", "(2, 4, 4, 9, 3)"});
    writeFileAtomic(dir + "/meta.json", meta);

    std::vector<double> pT = result_.pT;
    pT[3] = 1.5;
    writeNpy(dir + "/p_t.npy", pT.data(), {2, 4});
    testing::expectInputError([&] { loadRdm(dir); }, {"p_t.npy", "element 3", "[0, 1]"});
    pT[3] = NAN;
    writeNpy(dir + "/p_t.npy", pT.data(), {2, 4});
    testing::expectInputError([&] { loadRdm(dir); }, {"p_t.npy", "finite"});
    writeNpy(dir + "/p_t.npy", result_.pT.data(), {2, 4});

    std::vector<float> m = result_.rdmM;
    m[10] = -1.0f;
    writeNpy(dir + "/rdm_m.npy", m.data(), {2, 4, 4, 8, 3});
    testing::expectInputError([&] { loadRdm(dir); }, {"rdm_m.npy", "element 10"});
    std::filesystem::remove(dir + "/rdm_m.npy");
    testing::expectInputError([&] { loadRdm(dir); }, {"rdm_m.npy"});
}

}  // namespace
}  // namespace weft

namespace weft {
namespace {

TEST(RdmSliceImage, OneCellLightsItsPixelBlock) {
    // Incident bin 5, outgoing bin (theta_o row 2, phi_o column 7) of a
    // 2,4,4,8 grid: pixels x in [28, 32), y in [8, 12) at scale 4; rows are
    // theta_o from the top, columns phi_o from -180 degrees.
    const RdmBins bins{2, 4, 4, 8};
    std::vector<float> map(bins.incidentCount() * bins.outgoingCount() * 3, 0.0f);
    const size_t cell = (5 * bins.outgoingCount() + 2 * 8 + 7) * 3;
    map[cell] = 1.0f, map[cell + 1] = 2.0f, map[cell + 2] = 3.0f;
    const Image image = rdmSliceImage(map.data(), bins, 5, 4);
    ASSERT_EQ(image.width, 32);
    ASSERT_EQ(image.height, 16);
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 32; ++x) {
            const bool inside = x >= 28 && y >= 8 && y < 12;
            EXPECT_EQ(image.get(x, y), inside ? Rgb(1, 2, 3) : Rgb()) << x << " " << y;
        }
}

}  // namespace
}  // namespace weft
