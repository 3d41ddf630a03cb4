// Hostile input (issue 18): every example of the issue gets a clear exit 2
// naming the field or file (or, where the input is legitimate, a correct
// finite result); no output replaces an input; a signal leaves no temporary
// output behind.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <string>
#include <thread>

#include "cli_test_util.h"
#include "weft/core/file.h"
#include "weft/core/image.h"
#include "weft/core/image_io.h"

namespace weft {
namespace {

using testing::expectUserError;
using testing::RunResult;

const std::string kFleece = std::string(WEFT_SOURCE_DIR) + "/tests/data/fleece-small.json";

class HostileCliTest : public testing::CliTestBase {
  protected:
    void SetUp() override {
        CliTestBase::SetUp();
        writeFileAtomic(path("yarn.txt"), "-0.2 0 0\n0 0.01 0\n0.2 0 0\n");
    }
    // A tiny scene with the given camera and lights (JSON text).
    void writeScene(const std::string& name, const std::string& camera,
                    const std::string& lights = "[]") {
        writeFileAtomic(path(name), R"({"camera": )" + camera + R"(,
            "film": {"width": 8, "height": 6}, "render": {"spp": 1, "seed": 1},
            "lights": )" + lights + R"(,
            "yarns": [{"curves": "yarn.txt", "radius": 0.03, "model": ")" +
                                        kFleece + R"("}]})");
    }
    static const char* camera() { return R"({"from": [0, 0, 1], "to": [0, 0, 0], "fov_deg": 8})"; }
};

TEST_F(HostileCliTest, ExtremeSceneNumbersAreRefusedOrHandled) {
    // Refused, naming the field and the range, instead of an Embree assertion.
    writeScene("far.json", R"({"from": [1.9e18, 0, 1], "to": [0, 0, 0]})");
    expectUserError(run("render far.json --out a.exr"),
                    {"far.json", "camera.from[0] = 1.9e+18", "[-1e+06, 1e+06] scene units"});
    writeScene(
        "light.json", camera(),
        R"([{"type": "sphere", "center": [1e155, 0, 0], "radius": 1, "radiance": [1, 1, 1]}])");
    expectUserError(run("render light.json --out a.exr"), {"light.json", "center[0]"});
    writeScene("sky.json", camera(), R"([{"type": "sky", "scale": 1e308}])");
    expectUserError(run("render sky.json --out a.exr"),
                    {"sky.json", "scale = 1e+308", "[0, 1e+06]"});
    // A curve point beyond the range, once scaled.
    writeFileAtomic(path("far.txt"), "0 0 0\n1000001 0 0\n");
    writeFileAtomic(path("far-curve.json"), R"({"camera": )" + std::string(camera()) + R"(,
        "yarns": [{"curves": "far.txt", "radius": 0.03, "model": ")" + kFleece + R"("}]})");
    expectUserError(run("render far-curve.json --out a.exr"),
                    {"far-curve.json: yarns[0]", "curve 0, point 1 (1000001, 0, 0) times scale 1",
                     "within +-1e+06 scene units"});
    // Legitimate, however small: a tiny up vector and a sub-normal view distance.
    writeScene("up.json", R"({"from": [0, 0, 1], "to": [0, 0, 0], "up": [0, 1e-300, 0]})");
    writeScene("close.json", R"({"from": [0, 0, 0], "to": [0, 0, 5e-324], "up": [0, 1, 0]})");
    for (const std::string scene : {"up", "close"}) {
        const RunResult r = run("render " + scene + ".json --quiet --out " + scene + "-out.exr");
        ASSERT_EQ(r.status, 0) << r.err;
        for (float v : readImage(path(scene + "-out.exr")).pixels) ASSERT_TRUE(std::isfinite(v));
    }
}

TEST_F(HostileCliTest, CountsAndSeedsThatWouldWrapAreRefused) {
    // A flag error from the command-line parser: exit 2 and its message.
    const RunResult seed = run("render x.json --seed -1 --out a.exr");
    EXPECT_EQ(seed.status, 2);
    EXPECT_TRUE(
        testing::contains(seed.err, "--seed: a seed is an integer in [0, 2^64 - 1], got -1"))
        << seed.err;
    expectUserError(run("gather --preset fleece --paths 9223372036854775807 --out g"),
                    {"paths = 9223372036854775807", "[1, 2147483648]"});
    EXPECT_FALSE(std::filesystem::exists(path("g")));
}

TEST_F(HostileCliTest, SubnormalDirectionsAreNormalised) {
    ASSERT_EQ(run("fiber sample --preset fleece --wi 1e-320,0,0 --count 10 --out tiny.npy").status,
              0);
    ASSERT_EQ(run("fiber sample --preset fleece --wi 1,0,0 --count 10 --out unit.npy").status, 0);
    EXPECT_EQ(readFile(path("tiny.npy")), readFile(path("unit.npy")));
    const RunResult r = run("yarn sample --model " + testing::shellQuote(kFleece) +
                            " --wi 0,0,1e-320 --count 4 --out y.npy");
    EXPECT_EQ(r.status, 0) << r.err;
}

TEST_F(HostileCliTest, OutputsNeverReplaceInputs) {
    writeScene("scene.json", camera());
    const std::string sceneText = readFile(path("scene.json"));
    // The statistics file of --out scene.exr would be scene.json: it is
    // scene.render.json instead (docs/render.md).
    RunResult r = run("render scene.json --quiet --out scene.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_TRUE(std::filesystem::exists(path("scene.render.json")));
    EXPECT_EQ(readFile(path("scene.json")), sceneText);
    ASSERT_EQ(run("render scene.json --quiet --out a.exr").status, 0);
    ASSERT_EQ(run("render scene.json --quiet --out b.exr").status, 0);
    const std::string a = readFile(path("a.exr"));
    expectUserError(run("compare a.exr b.exr --json a.exr"), {"--json 'a.exr'", "image A"});
    expectUserError(run("compare a.exr b.exr --heatmap b.exr"), {"--heatmap 'b.exr'", "image B"});
    expectUserError(run("compare a.exr b.exr --heatmap h.png --json h.png"),
                    {"name the same file"});
    expectUserError(run("montage a.exr a.png --out a.png"), {"--out 'a.png'", "input image 2"});
    EXPECT_EQ(readFile(path("a.exr")), a);
    ASSERT_EQ(run("fiber sample --preset fleece --wi 0,1,0 --count 4 --out s.npy").status, 0);
    expectUserError(run("fiber eval --preset fleece --in s.npy --out s.npy"),
                    {"--out 's.npy'", "--in 's.npy'"});
    // A hard link is the same file.
    std::filesystem::create_hard_link(path("scene.json"), path("linked.json"));
    r = run("render scene.json --quiet --out linked.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_TRUE(std::filesystem::exists(path("linked.render.json")));
    EXPECT_EQ(readFile(path("scene.json")), sceneText);
}

TEST_F(HostileCliTest, InputsThatAreNotRegularFilesOrTooLargeAreRefused) {
    std::filesystem::create_symlink("/dev/zero", path("zero.json"));
    expectUserError(run("yarn sample --model zero.json --wi 0,0,1 --count 1 --out s.npy"),
                    {"zero.json", "not a regular file"});
    // The child inherits the limit from this process's environment.
    ASSERT_EQ(::setenv("WEFT_MAX_INPUT_BYTES", "1K", 1), 0);
    const RunResult r = run("yarn sample --model " + testing::shellQuote(kFleece) +
                            " --wi 0,0,1 --count 1 --out s.npy");
    ::unsetenv("WEFT_MAX_INPUT_BYTES");
    expectUserError(
        r, {"fleece-small.json", "over the input size limit of 1.0 KB", "WEFT_MAX_INPUT_BYTES"});
}

TEST_F(HostileCliTest, MemoryBudgetRefusesBeforeAllocating) {
    ASSERT_EQ(::setenv("WEFT_MEMORY_BUDGET", "64M", 1), 0);
    const RunResult gather =
        run("gather --preset fleece --paths 10 --bins 100,100,100,100 --out g");
    writeFileAtomic(path("scene.json"), R"({"camera": {"from": [0, 0, 1], "to": [0, 0, 0]},
        "film": {"width": 16384, "height": 16384},
        "yarns": [{"curves": "yarn.txt", "radius": 0.03, "model": ")" +
                                            kFleece + R"("}]})");
    const RunResult render = run("render scene.json --out big.exr");
    ::unsetenv("WEFT_MEMORY_BUDGET");
    expectUserError(gather, {"the RDM's bins (100,100,100,100) needs about 9.6 GB",
                             "memory budget of 67 MB", "WEFT_MEMORY_BUDGET"});
    EXPECT_FALSE(std::filesystem::exists(path("g")));
    expectUserError(render, {"scene.json: the film (16384 x 16384) needs about 15 GB"});
}

TEST_F(HostileCliTest, EnvmapMustLoadWhenTheSceneIsWritten) {
    Image sky(8, 4);
    for (float& v : sky.pixels) v = 0.5f;
    writeExr(path("sky.exr"), sky);
    const std::string bytes = readFile(path("sky.exr"));
    writeFileAtomic(path("cut.exr"), bytes.substr(0, bytes.size() / 2));
    expectUserError(
        run("scene closeup --model " + testing::shellQuote(kFleece) + " --envmap cut.exr --out s"),
        {"--envmap", "cut.exr"});
    EXPECT_FALSE(std::filesystem::exists(path("s")));
}

// SIGTERM during a gather: the DIR.tmp.<pid>/ it was writing is removed and
// the process dies of the signal.
TEST_F(HostileCliTest, SignalsRemoveTemporaryOutputs) {
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        if (::chdir(dir_.c_str()) != 0) ::_exit(127);
        ::execl(WEFT_BIN, WEFT_BIN, "gather", "--preset", "fleece", "--paths", "2000000000",
                "--threads", "1", "--quiet", "--out", "g", static_cast<char*>(nullptr));
        ::_exit(127);
    }
    const std::string temp = path("g.tmp." + std::to_string(child));
    for (int k = 0; k < 600 && !std::filesystem::exists(temp); ++k)
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    EXPECT_TRUE(std::filesystem::exists(temp));
    ASSERT_EQ(::kill(child, SIGTERM), 0);
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << status;
    EXPECT_FALSE(std::filesystem::exists(temp));
    EXPECT_FALSE(std::filesystem::exists(path("g")));
}

}  // namespace
}  // namespace weft
