// End-to-end tests of `weft view` (issue 44, docs/view.md): bad flags and
// scenes are exit 2 before anything is served; a running view prints its
// address, serves it, and stops cleanly on SIGINT and on SIGTERM (exit 0).
#include <fcntl.h>
#include <httplib.h>

#include <chrono>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <thread>

#include "cli_test_util.h"

namespace weft {
namespace {

using testing::RunResult;
using testing::statusOf;

class ViewCliTest : public testing::CliTestBase {
  protected:
    void writeScene() {
        writeFileAtomic(path("yarn.txt"), "-0.2 0 0\n0.2 0 0\n");
        writeFileAtomic(path("scene.json"),
                        std::string(R"({"camera": {"from": [0, 0, 1], "to": [0, 0, 0]},
            "film": {"width": 24, "height": 24}, "render": {"spp": 2},
            "yarns": [{"curves": "yarn.txt", "radius": 0.03, "model": ")") +
                            WEFT_SOURCE_DIR + "/tests/data/fleece-small.json\"}]}");
    }
};

TEST_F(ViewCliTest, BadFlagsAndScenesAreRefusedBeforeServing) {
    writeScene();
    testing::expectUserError(run("view scene.json --port 70000"), {"--port 70000", "[0, 65535]"});
    testing::expectUserError(run("view missing.json"), {"missing.json"});
    testing::expectUserError(run("view scene.json --spp 100000"), {"--spp 100000"});
    testing::expectUserError(run("view scene.json --models-dir nowhere"),
                             {"--models-dir nowhere", "not a folder"});
    testing::expectUserError(run("view scene.json --model yarn.txt"), {"yarn.txt"});
    testing::expectUserError(run("view scene.json --bind 203.0.113.7"),
                             {"cannot listen on 203.0.113.7"});
}

TEST_F(ViewCliTest, ServesItsAddressAndStopsCleanlyOnASignal) {
    writeScene();
    for (const int signal : {SIGINT, SIGTERM}) {
        int out[2];
        ASSERT_EQ(::pipe2(out, O_CLOEXEC), 0);
        const int devNull = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
        const pid_t child =
            testing::spawnWeft(dir_, "view scene.json --port 0 --threads 1", 0, out[1], devNull);
        ::close(out[1]);
        ::close(devNull);
        // The first line: "weft view: http://127.0.0.1:PORT/ (...)".
        std::string line;
        char c;
        while (::read(out[0], &c, 1) == 1 && c != '\n') line += c;
        ::close(out[0]);
        const std::string prefix = "http://127.0.0.1:";
        const size_t at = line.find(prefix);
        ASSERT_NE(at, std::string::npos) << line;
        const int port = std::atoi(line.c_str() + at + prefix.size());
        ASSERT_GT(port, 0) << line;
        httplib::Client client("127.0.0.1", port);
        client.set_read_timeout(30, 0);
        auto state = client.Get("/api/state");
        ASSERT_TRUE(state);
        EXPECT_EQ(state->status, 200);
        EXPECT_EQ(nlohmann::json::parse(state->body)["film"]["width"], 24);
        ::kill(child, signal);
        int wstatus = 0;
        ::waitpid(child, &wstatus, 0);
        EXPECT_EQ(statusOf(wstatus), 0) << "signal " << signal;
        EXPECT_FALSE(client.Get("/api/state")) << "still serving after the signal";
    }
}

}  // namespace
}  // namespace weft
