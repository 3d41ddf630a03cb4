// Helpers for the end-to-end tests of the `weft` binary (WEFT_BIN): a fixture
// with a fresh working directory that runs `weft ARGS` there and captures
// exit status, stdout and stderr.
#pragma once

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <sstream>
#include <string>
#include <vector>

#include "weft/core/file.h"
#include "weft/core/test_util.h"

namespace weft::testing {

struct RunResult {
    int status = -1;  // exit status; -signal if the process was killed by a signal
    std::string out;  // stdout
    std::string err;  // stderr
};

// Single-quotes `s` for /bin/sh.
inline std::string shellQuote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

inline bool contains(const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
}

// Exit status 2, a "weft: error: " message on stderr containing every part.
inline void expectUserError(const RunResult& r, std::initializer_list<std::string> parts) {
    EXPECT_EQ(r.status, 2) << "stdout: " << r.out << "\nstderr: " << r.err;
    EXPECT_TRUE(contains(r.err, "weft: error: ")) << "stderr: " << r.err;
    for (const std::string& p : parts)
        EXPECT_TRUE(contains(r.err, p)) << "stderr '" << r.err << "' lacks '" << p << "'";
}

// Starts `weft ARGS` (ARGS split at spaces) in `dir` with its soft file-size
// limit at `fileSizeLimit` (0: unchanged) and SIGXFSZ, SIGINT, SIGTERM and
// SIGHUP at their default actions,
// whatever this process inherited: what the binary does on its own is tested.
// stdout and stderr go to the given descriptors. Only async-signal-safe calls
// between fork and exec.
inline pid_t spawnWeft(const std::filesystem::path& dir, const std::string& args,
                       rlim_t fileSizeLimit, int outFd, int errFd) {
    std::vector<std::string> words{WEFT_BIN};
    std::istringstream split(args);
    for (std::string w; split >> w;) words.push_back(w);
    std::vector<char*> argv;
    for (std::string& w : words) argv.push_back(w.data());
    argv.push_back(nullptr);
    const std::string where = dir.string();
    rlimit limit{};
    ::getrlimit(RLIMIT_FSIZE, &limit);
    if (fileSizeLimit > 0) limit.rlim_cur = fileSizeLimit;
    const pid_t child = ::fork();
    if (child == 0) {
        struct sigaction dfl {};
        dfl.sa_handler = SIG_DFL;
        // And the signals the tests send at their default actions, even
        // where this process was started with them ignored (a background job).
        for (int s : {SIGXFSZ, SIGINT, SIGTERM, SIGHUP}) ::sigaction(s, &dfl, nullptr);
        if (::chdir(where.c_str()) != 0 || ::setrlimit(RLIMIT_FSIZE, &limit) != 0 ||
            ::dup2(outFd, 1) < 0 || ::dup2(errFd, 2) < 0)
            ::_exit(127);
        ::execv(argv[0], argv.data());
        ::_exit(127);
    }
    return child;
}

// The exit status as RunResult keeps it: -signal when killed by one.
inline int statusOf(int wstatus) {
    if (WIFEXITED(wstatus)) return WEXITSTATUS(wstatus);
    if (WIFSIGNALED(wstatus)) return -WTERMSIG(wstatus);
    return -1000;
}

class CliTestBase : public TempDirTest {
protected:
    void SetUp() override {
        TempDirTest::SetUp();
        errFile_ = dir_.string() + ".stderr";
    }
    void TearDown() override {
        std::error_code ignored;
        std::filesystem::remove(errFile_, ignored);
        TempDirTest::TearDown();
    }

    // Runs `weft ARGS` (ARGS is shell text) inside the test directory.
    RunResult run(const std::string& args) const {
        const std::string cmd = "cd " + shellQuote(dir_.string()) + " && " + shellQuote(WEFT_BIN) +
                                " " + args + " 2>" + shellQuote(errFile_);
        RunResult r;
        FILE* pipe = ::popen(cmd.c_str(), "r");
        if (!pipe) {
            ADD_FAILURE() << "popen failed for: " << cmd;
            return r;
        }
        char buf[4096];
        size_t n;
        while ((n = std::fread(buf, 1, sizeof buf, pipe)) > 0) r.out.append(buf, n);
        const int st = ::pclose(pipe);
        if (WIFEXITED(st)) {
            r.status = WEXITSTATUS(st);
        } else if (WIFSIGNALED(st)) {
            r.status = -WTERMSIG(st);
        }
        r.err = std::filesystem::exists(errFile_) ? readFile(errFile_) : std::string();
        return r;
    }

    // Names of the entries in the test directory, sorted.
    std::vector<std::string> listing() const {
        std::vector<std::string> names;
        for (const auto& e : std::filesystem::directory_iterator(dir_))
            names.push_back(e.path().filename());
        std::sort(names.begin(), names.end());
        return names;
    }

    std::string errFile_;
};

}  // namespace weft::testing
