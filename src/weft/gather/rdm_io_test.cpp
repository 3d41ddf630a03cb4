#include "weft/gather/rdm_io.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "weft/core/file.h"
#include "weft/core/npy.h"
#include "weft/core/test_util.h"
#include "weft/gather/gather.h"

namespace weft {
namespace {

class RdmIoTest : public testing::TempDirTest {
protected:
    // A small gather written to DIR/g.
    std::string writeSmallGather(GatherOptions* used = nullptr) {
        GatherOptions o;
        o.fiber = findMaterialPreset("fleece").fiber;
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
