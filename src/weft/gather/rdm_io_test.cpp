#include "weft/gather/rdm_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

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

// Issue 41, item 9: `weft fit` read a gather whose truncated.npy or depth.npy
// was damaged (NaN, negative, a declared shape of 2^40, cut short) and
// succeeded. loadRdm checks every file of the gather now.
TEST_F(RdmIoTest, DamagedCountsDepthAndTruncatedAreRefused) {
    const std::string dir = writeSmallGather();
    const auto refused = [&](std::initializer_list<std::string> words) {
        testing::expectInputError([&] { loadRdm(dir); }, words);
    };
    // truncated.npy (2,4,3): NaN, negative, weight where no path was truncated.
    ASSERT_EQ(result_.depth.back(), 0);
    std::vector<double> t = result_.truncated;
    t[4] = NAN;
    writeNpy(dir + "/truncated.npy", t.data(), {2, 4, 3});
    refused({dir + "/truncated.npy", "element 4 (0, 1, 1) is nan", "finite number >= 0"});
    t[4] = -1;
    writeNpy(dir + "/truncated.npy", t.data(), {2, 4, 3});
    refused({dir + "/truncated.npy", "element 4 (0, 1, 1) is -1"});
    t[4] = 0.25;
    writeNpy(dir + "/truncated.npy", t.data(), {2, 4, 3});
    refused({dir + "/truncated.npy", "element 4", "no truncated path"});
    std::filesystem::remove(dir + "/truncated.npy");
    refused({dir + "/truncated.npy"});
    writeNpy(dir + "/truncated.npy", result_.truncated.data(), {2, 4, 3});

    // depth.npy (1002): negative, not summing to the paths, float with a NaN,
    // a declared shape of 2^40, cut short.
    const std::string depthPath = dir + "/depth.npy";
    std::vector<int64_t> d = result_.depth;
    d[3] = -1;
    writeNpy(depthPath, d.data(), {d.size()});
    refused({depthPath, "element 3 is -1", "[0, 2000]"});
    d = result_.depth;
    d[3] += 1;
    writeNpy(depthPath, d.data(), {d.size()});
    refused({depthPath, "sum to 2001", "2000 paths"});
    std::vector<double> nan(d.size(), NAN);
    writeNpy(depthPath, nan.data(), {nan.size()});
    refused({depthPath, "expected <i8 of shape (1002,)"});
    const std::string header =
        "{'descr': '<i8', 'fortran_order': False, 'shape': (1099511627776,), }";
    std::string huge = std::string("\x93NUMPY\x01\x00", 8);
    const size_t padded = (10 + header.size() + 1 + 63) / 64 * 64 - 10;
    huge += static_cast<char>(padded & 0xff);
    huge += static_cast<char>(padded >> 8);
    huge += header + std::string(padded - header.size() - 1, ' ') + "\n" + std::string(64, '\0');
    writeFileAtomic(depthPath, huge);
    refused({depthPath, "1099511627776"});
    const std::string bytes = encodeNpy(result_.depth.data(), {result_.depth.size()});
    writeFileAtomic(depthPath, bytes.substr(0, bytes.size() - 12));
    refused({depthPath, "truncated"});
    // Depth 0 must be the T paths.
    d = result_.depth;
    d[0] -= 1, d[1] += 1;
    writeNpy(depthPath, d.data(), {d.size()});
    refused({depthPath, "element 0", "count_t.npy"});
    writeNpy(depthPath, result_.depth.data(), {result_.depth.size()});

    // count_t.npy beyond count.npy; p_t.npy in [0, 1] but not count_t / count.
    std::vector<int64_t> ct = result_.countT;
    ct[5] = result_.count[5] + 1;
    writeNpy(dir + "/count_t.npy", ct.data(), {2, 4});
    refused({dir + "/count_t.npy", "element 5 (1, 1)", "more than"});
    writeNpy(dir + "/count_t.npy", result_.countT.data(), {2, 4});
    std::vector<double> pT = result_.pT;
    pT[2] = pT[2] > 0.5 ? pT[2] - 0.25 : pT[2] + 0.25;
    writeNpy(dir + "/p_t.npy", pT.data(), {2, 4});
    refused({dir + "/p_t.npy", "element 2 (0, 2)", "count_t.npy / count.npy"});
    writeNpy(dir + "/p_t.npy", result_.pT.data(), {2, 4});

    // exit_distance.npy, when there is one.
    std::vector<double> e = result_.exitDistance;
    e[7] = -0.5;
    writeNpy(dir + "/exit_distance.npy", e.data(), {129, 3});
    refused({dir + "/exit_distance.npy", "element 7 (2, 1) is -0.5"});
    std::filesystem::remove(dir + "/exit_distance.npy");
    EXPECT_NO_THROW(loadRdm(dir));  // a recoloured gather has none
}

TEST_F(RdmIoTest, APlyDescriptionOrLinkedFilesAreRefused) {
    const std::string dir = writeSmallGather();
    const std::string meta = readFile(dir + "/meta.json");
    for (const char* field : {"radius", "fiber_radius", "period", "segments"}) {
        for (const double factor : {0.0, -1.0, 1e30}) {
            nlohmann::json j = nlohmann::json::parse(meta);
            j["ply"][field] = j["ply"][field].get<double>() * factor;
            writeFileAtomic(dir + "/meta.json", j.dump());
            testing::expectInputError([&] { loadRdm(dir); },
                                      {dir + "/meta.json", std::string("ply.") + field});
        }
        nlohmann::json j = nlohmann::json::parse(meta);
        j["ply"].erase(field);
        writeFileAtomic(dir + "/meta.json", j.dump());
        testing::expectInputError([&] { loadRdm(dir); }, {dir + "/meta.json", field, "missing"});
    }
    writeFileAtomic(dir + "/meta.json", meta);
    // rdm_m.npy a link to rdm_r.npy: the R map would be fitted as M.
    std::filesystem::rename(dir + "/rdm_m.npy", path("rdm_m.npy"));
    std::filesystem::create_symlink(dir + "/rdm_r.npy", dir + "/rdm_m.npy");
    testing::expectInputError([&] { loadRdm(dir); },
                              {dir + "/rdm_m.npy", dir + "/rdm_r.npy", "one file"});
    std::filesystem::remove(dir + "/rdm_m.npy");
    std::filesystem::create_hard_link(dir + "/count.npy", dir + "/rdm_m.npy");
    testing::expectInputError([&] { loadRdm(dir); }, {"rdm_m.npy", "count.npy", "one file"});
    std::filesystem::remove(dir + "/rdm_m.npy");
    std::filesystem::rename(path("rdm_m.npy"), dir + "/rdm_m.npy");
    EXPECT_NO_THROW(loadRdm(dir));
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
