// Sharded gathers: the shard ranges, and the merge of the parts against an
// unsharded gather of the same paths (independent truth: one run over all paths).
#include "weft/gather/gather_merge.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/npy.h"
#include "weft/core/test_util.h"
#include "weft/gather/gather_folder.h"

namespace weft {
namespace {

TEST(Shard, ParsesKOverN) {
    const Shard s = Shard::parse("3/8", "--shard");
    EXPECT_EQ(s.index, 3);
    EXPECT_EQ(s.count, 8);
    EXPECT_EQ(s.toString(), "3/8");
    EXPECT_TRUE(Shard::parse("0/1", "--shard").whole());
    for (const char* bad : {"", "3", "/4", "3/", "4/4", "5/4", "-1/4", "1/0", "+1/4", "1/4/5",
                            "a/b", " 1/4", "1/70000", "1.5/4"}) {
        try {
            Shard::parse(bad, "--shard");
            ADD_FAILURE() << "accepted \"" << bad << "\"";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("--shard"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("K/N"), std::string::npos) << e.what();
        }
    }
}

TEST(Shard, RangesAreDisjointCoverEverythingAndDifferByAtMostOne) {
    for (int64_t total : {int64_t{1}, int64_t{2}, int64_t{7}, int64_t{1000}, int64_t{1001}, kMaxPaths}) {
        for (int64_t n : {1, 2, 3, 7, 64}) {
            if (n > total) continue;
            int64_t next = 0, smallest = total, largest = 0;
            for (int64_t k = 0; k < n; ++k) {
                const Shard s{k, n};
                EXPECT_EQ(s.begin(total), next) << k << "/" << n << " of " << total;
                next = s.end(total);
                smallest = std::min(smallest, s.end(total) - s.begin(total));
                largest = std::max(largest, s.end(total) - s.begin(total));
            }
            EXPECT_EQ(next, total);
            EXPECT_LE(largest - smallest, 1);
            EXPECT_GE(smallest, 1);
        }
    }
    EXPECT_THROW(Shard({0, 3}).validate(2, "--shard", "paths"), InputError);
    EXPECT_NO_THROW(Shard({1, 2}).validate(2, "--shard", "paths"));
}

class GatherMergeTest : public testing::TempDirTest {
  protected:
    static GatherOptions options() {
        GatherOptions o;
        o.fiber = {Rgb(0.04), Rgb(0.9, 0.7, 0.5), 7.0, 12.0, 25.0};
        o.ply = {24, 0.4, 0.5};
        o.paths = 2500;  // not a multiple of the shard counts or of the 1024-path tasks
        o.seed = 5;
        o.bins = {3, 8, 6, 12};
        o.maxDepth = 6;  // some paths are truncated, so sum_truncated is exercised
        o.threads = 2;
        o.quiet = true;
        return o;
    }

    // Writes the n parts of options() (threads alternating 1 and 2) and returns their directories.
    std::vector<std::string> writeParts(int64_t n, const std::string& prefix,
                                        GatherOptions o = options()) const {
        std::vector<std::string> dirs;
        for (int64_t k = 0; k < n; ++k) {
            o.shard = {k, n};
            o.threads = 1 + static_cast<int>(k % 2);
            TempDirCommit out(path(prefix + std::to_string(k)));
            writeGatherPart(gatherSums(o), o, out);
            dirs.push_back(out.finalPath());
        }
        return dirs;
    }

    std::string mergeError(const std::vector<std::string>& dirs) const {
        try {
            mergeGatherParts(dirs);
        } catch (const InputError& e) {
            return e.what();
        }
        ADD_FAILURE() << "the merge was accepted";
        return "";
    }
};

TEST_F(GatherMergeTest, MergedShardsEqualTheUnshardedGatherBitForBit) {
    const GatherResult whole = gatherRdm(options());
    ASSERT_GT(whole.stats.truncatedPaths, 0);
    for (int64_t n : {1, 3, 7}) {
        std::vector<std::string> dirs = writeParts(n, "n" + std::to_string(n) + "_");
        std::reverse(dirs.begin(), dirs.end());  // the order of the parts does not matter
        const MergedGather m = mergeGatherParts(dirs);
        EXPECT_EQ(m.shards, n);
        const GatherResult r = normaliseGather(m.sums, m.options, m.shards);
        EXPECT_EQ(r.count, whole.count) << n;
        EXPECT_EQ(r.countT, whole.countT) << n;
        EXPECT_EQ(r.depth, whole.depth) << n;
        EXPECT_EQ(r.pT, whole.pT) << n;
        EXPECT_EQ(r.rdmR, whole.rdmR) << n;
        EXPECT_EQ(r.rdmM, whole.rdmM) << n;
        EXPECT_EQ(r.truncated, whole.truncated) << n;
        EXPECT_EQ(r.exitDistance, whole.exitDistance) << n;
        EXPECT_EQ(r.exitOffset, whole.exitOffset) << n;
        EXPECT_FALSE(r.exitOffset.empty());
        EXPECT_EQ(r.plyLines.size(), whole.plyLines.size());
        EXPECT_EQ(r.stats.paths, whole.stats.paths);
        EXPECT_EQ(r.stats.rays, whole.stats.rays);
        EXPECT_EQ(r.stats.meanDepth, whole.stats.meanDepth);
        EXPECT_EQ(r.stats.truncatedPaths, whole.stats.truncatedPaths);
        EXPECT_EQ(r.stats.shards, n);
        // The merged meta.json says what was gathered exactly as the unsharded one.
        const nlohmann::json a = gatherMetadata(r, m.options), b = gatherMetadata(whole, options());
        for (const char* key : {"material", "fiber", "ply", "bins", "paths", "seed", "ply_seed",
                                "max_depth", "mean_depth", "truncated_energy"})
            EXPECT_EQ(a.at(key), b.at(key)) << key;
    }
}

TEST_F(GatherMergeTest, APartWithoutExitOffsetsLeavesTheMergeWithout) {
    // A part written before the offsets were recorded: the merge has none
    // (rather than the other parts' share of them); everything else is whole.
    const GatherResult whole = gatherRdm(options());
    const std::vector<std::string> dirs = writeParts(3, "old_");
    std::filesystem::remove(dirs[1] + "/sum_exit_offset.npy");
    const MergedGather m = mergeGatherParts(dirs);
    const GatherResult r = normaliseGather(m.sums, m.options, m.shards);
    EXPECT_TRUE(r.exitOffset.empty());
    EXPECT_EQ(r.rdmM, whole.rdmM);
    EXPECT_EQ(r.exitDistance, whole.exitDistance);
}

TEST_F(GatherMergeTest, PartsThatDoNotFormOneGatherAreRejected) {
    const std::vector<std::string> parts = writeParts(3, "p");
    const auto expectMessage = [&](const std::vector<std::string>& dirs,
                                   std::initializer_list<const char*> words) {
        const std::string message = mergeError(dirs);
        for (const char* w : words)
            EXPECT_NE(message.find(w), std::string::npos) << "\"" << w << "\" in: " << message;
    };
    // A shard twice, a shard missing.
    expectMessage({parts[0], parts[1], parts[1]}, {"both shard 1/3", parts[1].c_str()});
    expectMessage({parts[0], parts[2]}, {"missing", "1/3"});
    expectMessage({}, {"no gather parts"});
    // Another gather's shard: other bins, seed, material, max depth, shard count.
    GatherOptions other = options();
    other.bins = {3, 8, 6, 6};
    expectMessage({parts[0], parts[1], writeParts(3, "bins", other)[2]}, {"\"bins\"", "bins2/meta.json"});
    other = options();
    other.seed = 6;
    expectMessage({parts[0], parts[1], writeParts(3, "seed", other)[2]}, {"\"seed\""});
    other = options();
    other.material = "silk";
    expectMessage({parts[0], parts[1], writeParts(3, "mat", other)[2]}, {"\"material\""});
    other = options();
    other.fiber.betaRDeg = 8.0;
    expectMessage({parts[0], parts[1], writeParts(3, "fib", other)[2]}, {"\"fiber\""});
    expectMessage({parts[0], parts[1], writeParts(4, "four")[2]}, {"\"shard.count\""});
    // Not a part at all: a whole gather, a missing directory.
    {
        TempDirCommit out(path("whole"));
        writeGather(gatherRdm(options()), options(), out);
    }
    expectMessage({path("whole")}, {"whole/meta.json", "not a shard"});
    expectMessage({path("nowhere")}, {"nowhere/meta.json"});
}

TEST_F(GatherMergeTest, DamagedArraysAreRejected) {
    const std::vector<std::string> parts = writeParts(2, "p");
    // A truncated array.
    const std::string sumM = parts[1] + "/sum_m.npy";
    const std::string bytes = readFile(sumM);
    writeFileAtomic(sumM, bytes.substr(0, bytes.size() - 8));
    EXPECT_NE(mergeError(parts).find("sum_m.npy"), std::string::npos);
    writeFileAtomic(sumM, bytes);
    // Counts that do not add up to the shard's paths.
    const std::string countPath = parts[0] + "/count.npy";
    NpyArray count = readNpy(countPath);
    std::vector<int64_t> counts(count.size());
    std::memcpy(counts.data(), count.bytes.data(), count.bytes.size());
    counts[0] += 1;
    writeNpy(countPath, counts.data(), count.shape);
    const std::string message = mergeError(parts);
    EXPECT_NE(message.find(parts[0]), std::string::npos) << message;
    EXPECT_NE(message.find("1250 paths"), std::string::npos) << message;
    // A negative weight.
    counts[0] -= 1;
    writeNpy(countPath, counts.data(), count.shape);
    NpyArray r = readNpy(parts[0] + "/sum_r.npy");
    std::vector<int64_t> sums(r.size());
    std::memcpy(sums.data(), r.bytes.data(), r.bytes.size());
    sums[5] = -1;
    writeNpy(parts[0] + "/sum_r.npy", sums.data(), r.shape);
    const std::string negative = mergeError(parts);
    EXPECT_NE(negative.find("sum_r.npy: element 5 (0, 0, 0, 1, 2) is -1"), std::string::npos)
        << negative;
    EXPECT_NE(negative.find(">= 0"), std::string::npos) << negative;
}

// Item 9 of issue 41: a part's meta.json must describe the ply it was traced
// on, every part must say the same, and every file must be its own.
class GatherPartDamageTest : public GatherMergeTest {
  protected:
    static nlohmann::json readMeta(const std::string& dir) {
        return nlohmann::json::parse(readFile(dir + "/meta.json"));
    }
    static void writeMeta(const std::string& dir, const nlohmann::json& meta) {
        writeFileAtomic(dir + "/meta.json", meta.dump(2));
    }
    // mergeError(dirs) contains each of `words`.
    void expectRefused(const std::vector<std::string>& dirs,
                       std::initializer_list<std::string> words) const {
        const std::string message = mergeError(dirs);
        for (const std::string& w : words)
            EXPECT_NE(message.find(w), std::string::npos) << "\"" << w << "\" in: " << message;
    }
};

TEST_F(GatherPartDamageTest, PlyDescriptionsThatAreNotTheTracedPlyAreRefused) {
    const std::vector<std::string> one = writeParts(1, "one"), two = writeParts(2, "two");
    // Scaled by 0, -1 and 1e30, off by one unit in the last place, removed, retyped.
    const std::vector<std::pair<std::string, std::function<void(nlohmann::json&)>>> damage = {
        {"times 0", [](nlohmann::json& v) { v = v.get<double>() * 0; }},
        {"times -1", [](nlohmann::json& v) { v = -v.get<double>(); }},
        {"times 1e30", [](nlohmann::json& v) { v = v.get<double>() * 1e30; }},
        {"next double", [](nlohmann::json& v) { v = std::nextafter(v.get<double>(), 1e300); }},
        {"removed", [](nlohmann::json& v) { v = nullptr; }},
        {"a string", [](nlohmann::json& v) { v = v.dump(); }}};
    for (const char* field : {"radius", "segments", "period", "fiber_radius"})
        for (const auto& [how, change] : damage)
            for (const std::vector<std::string>* parts : {&one, &two}) {
                const std::string& dir = parts->back();
                const std::string original = readFile(dir + "/meta.json");
                nlohmann::json meta = nlohmann::json::parse(original);
                nlohmann::json& ply = meta.at("ply");
                if (field == std::string("segments") && how == std::string("next double"))
                    ply.at(field) = ply.at(field).get<int64_t>() + 1;  // an integer field
                else
                    change(ply.at(field));
                if (ply.at(field).is_null()) ply.erase(field);
                writeMeta(dir, meta);
                SCOPED_TRACE(std::string(field) + " " + how + " in " + dir);
                expectRefused(*parts, {dir + "/meta.json", field});
                writeFileAtomic(dir + "/meta.json", original);
            }
    EXPECT_NO_THROW(mergeGatherParts(one));
    EXPECT_NO_THROW(mergeGatherParts(two));
}

TEST_F(GatherPartDamageTest, EveryFieldOfTheGatheredInputsIsSharedByThePartsOrChecked) {
    // Each leaf of gatherInputs() lies under a field of the list, but the
    // Embree version (the same weft can link another Embree).
    GatherOptions o = options();
    const nlohmann::json inputs = gatherInputs(o, 0.1, 2.0, 100);
    const nlohmann::json leaves = inputs.flatten();
    for (const auto& [pointer, value] : leaves.items()) {
        std::string path = pointer.substr(1);
        std::replace(path.begin(), path.end(), '/', '.');
        if (path == "versions.embree") continue;
        bool covered = false;
        for (std::string_view field : sharedPartFields())
            covered = covered || path == field || path.rfind(std::string(field) + ".", 0) == 0;
        EXPECT_TRUE(covered) << path << " is not in sharedPartFields()";
    }
    // And each of them, changed in one part, is refused naming it.
    const std::vector<std::string> parts = writeParts(2, "p");
    const std::string original = readFile(parts[1] + "/meta.json");
    for (std::string_view field : sharedPartFields()) {
        nlohmann::json meta = nlohmann::json::parse(original);
        nlohmann::json* v = &meta;
        std::string rest(field);
        for (size_t dot; (dot = rest.find('.')) != std::string::npos; rest = rest.substr(dot + 1))
            v = &v->at(rest.substr(0, dot));
        v->at(rest) = nlohmann::json::array({"changed"});
        writeMeta(parts[1], meta);
        SCOPED_TRACE(std::string(field));
        const std::string message = mergeError(parts);
        EXPECT_NE(message.find(parts[1] + "/meta.json"), std::string::npos) << message;
        EXPECT_NE(message.find(rest), std::string::npos) << message;
    }
    // Valid values that differ from the other part's: the comparison names them.
    for (const auto& [object, key, value] :
         {std::tuple{"versions", "weft", "0.0.1"}, {"ply", "primitive", "spheres"}}) {
        nlohmann::json meta = nlohmann::json::parse(original);
        meta.at(object).at(key) = value;
        writeMeta(parts[1], meta);
        expectRefused(parts, {parts[1] + "/meta.json", parts[0] + "/meta.json",
                              "\"" + std::string(object) + "." + key + "\"",
                              "not shards of one gather"});
    }
    writeFileAtomic(parts[1] + "/meta.json", original);
    EXPECT_NO_THROW(mergeGatherParts(parts));
}

TEST_F(GatherPartDamageTest, ARemovedAnyColourFlagIsRefused) {
    GatherOptions o = options();
    o.anyColour = true;
    const std::vector<std::string> parts = writeParts(2, "ac", o);
    for (const std::string& dir : parts) {
        nlohmann::json meta = readMeta(dir);
        meta.erase("any_colour");
        writeMeta(dir, meta);
    }
    expectRefused(parts, {"meta.json", "\"any_colour\""});
    expectRefused({parts[0]}, {"meta.json", "\"any_colour\""});
}

TEST_F(GatherPartDamageTest, AMissingOrDifferentPlyTxtIsRefused) {
    const std::vector<std::string> parts = writeParts(2, "p");
    const std::string ply = readFile(parts[1] + "/ply.txt");
    std::filesystem::remove(parts[1] + "/ply.txt");
    expectRefused(parts, {parts[1] + "/ply.txt"});
    // One digit of one coordinate.
    std::string changed = ply;
    const size_t digit = changed.find_first_of("123456789", changed.size() / 2);
    changed[digit] = changed[digit] == '9' ? '8' : static_cast<char>(changed[digit] + 1);
    writeFileAtomic(parts[1] + "/ply.txt", changed);
    expectRefused(parts, {parts[1] + "/ply.txt", "line ", "differs"});
    // The same change in every part: still not the traced ply.
    writeFileAtomic(parts[0] + "/ply.txt", changed);
    expectRefused(parts, {"ply.txt", "differs"});
    writeFileAtomic(parts[0] + "/ply.txt", ply);
    writeFileAtomic(parts[1] + "/ply.txt", ply);
    EXPECT_NO_THROW(mergeGatherParts(parts));
}

TEST_F(GatherPartDamageTest, AFileLinkedToAnotherPartsIsRefused) {
    const std::vector<std::string> parts = writeParts(2, "p");
    const std::string own = parts[1] + "/sum_m.npy", saved = path("sum_m.npy");
    std::filesystem::rename(own, saved);
    std::filesystem::create_symlink(parts[0] + "/sum_m.npy", own);
    expectRefused(parts, {own, parts[0] + "/sum_m.npy", "one file", "inode"});
    std::filesystem::remove(own);
    std::filesystem::create_hard_link(parts[0] + "/sum_m.npy", own);
    expectRefused(parts, {own, parts[0] + "/sum_m.npy", "one file"});
    // Within one part: its R sums linked to its M sums.
    std::filesystem::remove(own);
    std::filesystem::create_symlink(std::filesystem::absolute(parts[1] + "/sum_r.npy"), own);
    expectRefused(parts, {own, parts[1] + "/sum_r.npy", "one file"});
    std::filesystem::remove(own);
    std::filesystem::rename(saved, own);
    EXPECT_NO_THROW(mergeGatherParts(parts));
}

TEST_F(GatherPartDamageTest, CountsThatContradictEachOtherAreRefused) {
    const std::vector<std::string> parts = writeParts(2, "p");
    const std::string dir = parts[1];
    const auto ints = [](const std::string& file) {
        const NpyArray a = readNpy(file);
        std::vector<int64_t> v(a.size());
        std::memcpy(v.data(), a.bytes.data(), a.bytes.size());
        return std::make_pair(v, a.shape);
    };
    const auto [count, incident] = ints(dir + "/count.npy");
    const auto [countT, incidentT] = ints(dir + "/count_t.npy");
    const auto [depth, depthShape] = ints(dir + "/depth.npy");
    // More T paths than paths in a bin.
    std::vector<int64_t> v = countT;
    v[2] = count[2] + 1;
    writeNpy(dir + "/count_t.npy", v.data(), incident);
    expectRefused(parts, {dir + "/count_t.npy", "element 2 (0, 2)", "more than"});
    writeNpy(dir + "/count_t.npy", countT.data(), incident);
    // Depth 0 (no interaction) must be the T paths: move one path to depth 1.
    v = depth;
    ASSERT_GT(v[0], 0);
    v[0] -= 1, v[1] += 1;
    writeNpy(dir + "/depth.npy", v.data(), depthShape);
    expectRefused(parts, {dir + "/depth.npy", "element 0", "count_t.npy"});
    // Interactions that meta.json's depth_sum does not count: one path one deeper.
    v = depth;
    ASSERT_GT(v[1], 0);
    v[1] -= 1, v[2] += 1;
    writeNpy(dir + "/depth.npy", v.data(), depthShape);
    expectRefused(parts, {dir + "/meta.json", "\"depth_sum\"", "depth.npy"});
    // A count beyond the part's paths.
    v = count;
    v[0] = int64_t{1} << 40;
    writeNpy(dir + "/count.npy", v.data(), incident);
    expectRefused(parts, {dir + "/count.npy", "element 0 (0, 0)", "in [0, 1250]"});
    writeNpy(dir + "/count.npy", count.data(), incident);
    writeNpy(dir + "/depth.npy", depth.data(), depthShape);
    EXPECT_NO_THROW(mergeGatherParts(parts));
}

}  // namespace
}  // namespace weft
