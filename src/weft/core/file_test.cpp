#include "weft/core/file.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <string>
#include <thread>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/test_util.h"

namespace weft {
namespace {

using namespace std::string_view_literals;
namespace fs = std::filesystem;

class FileTest : public testing::TempDirTest {
  protected:
    // Names of the entries of dir (not recursive), sorted.
    static std::vector<std::string> entries(const fs::path& dir) {
        std::vector<std::string> names;
        for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename());
        std::sort(names.begin(), names.end());
        return names;
    }
};

using testing::expectInputError;

TEST_F(FileTest, WriteThenReadBinaryBytes) {
    const std::string p = path("a.bin");
    const std::string_view bytes = "ab\0c\n\xff\r\n"sv;
    writeFileAtomic(p, bytes);
    EXPECT_EQ(readFile(p), bytes);
    // Overwrite with something shorter; nothing of the old content remains.
    writeFileAtomic(p, "x");
    EXPECT_EQ(readFile(p), "x");
    writeFileAtomic(p, "");
    EXPECT_EQ(readFile(p), "");
    // No temporary files are left behind.
    EXPECT_EQ(entries(dir_), std::vector<std::string>{"a.bin"});
}

TEST_F(FileTest, WriteLargeFile) {
    std::string big(5 << 20, '\0');
    for (size_t i = 0; i < big.size(); ++i) big[i] = static_cast<char>(i * 131 % 251);
    const std::string p = path("big.bin");
    writeFileAtomic(p, big);
    EXPECT_EQ(readFile(p), big);
}

TEST_F(FileTest, WriteWithoutDirectoryComponent) {
    const fs::path old = fs::current_path();
    fs::current_path(dir_);
    writeFileAtomic("plain.txt", "hello");
    EXPECT_EQ(readFile("plain.txt"), "hello");
    fs::current_path(old);
    EXPECT_EQ(entries(dir_), std::vector<std::string>{"plain.txt"});
}

TEST_F(FileTest, WriteFailuresNamePathAndReason) {
    const std::string missing = path("no/such/dir/out.txt");
    expectInputError([&] { writeFileAtomic(missing, "x"); },
                     {missing, "No such file or directory"});
    EXPECT_EQ(entries(dir_), std::vector<std::string>{});

    // The target is an existing directory: the rename fails, the temporary
    // file is removed.
    const std::string sub = path("sub");
    fs::create_directory(sub);
    expectInputError([&] { writeFileAtomic(sub, "x"); }, {sub, "Is a directory"});
    EXPECT_EQ(entries(dir_), std::vector<std::string>{"sub"});
    expectInputError([&] { writeFileAtomic(sub + "/", "x"); }, {sub + "/"});
    expectInputError([&] { writeFileAtomic("", "x"); }, {"empty path"});

    if (::geteuid() != 0) {  // root ignores permissions
        const std::string ro = path("ro");
        fs::create_directory(ro);
        fs::permissions(ro, fs::perms::owner_read | fs::perms::owner_exec);
        expectInputError([&] { writeFileAtomic(ro + "/f.txt", "x"); },
                         {ro + "/f.txt", "Permission denied"});
        fs::permissions(ro, fs::perms::owner_all);
        EXPECT_EQ(entries(ro), std::vector<std::string>{});
    }
}

TEST_F(FileTest, ReadFailuresNamePath) {
    const std::string missing = path("missing.txt");
    expectInputError([&] { readFile(missing); }, {missing, "No such file or directory"});
    expectInputError([&] { readFile(dir_.string()); }, {dir_.string(), "Is a directory"});
}

// Devices and FIFOs could be endless (a link to /dev/zero) or block (a FIFO
// without a writer): refused at once, naming the path.
TEST_F(FileTest, ReadRefusesFilesThatAreNotRegular) {
    expectInputError([] { readFile("/dev/zero"); }, {"'/dev/zero'", "not a regular file"});
    const std::string link = path("zero.json");
    fs::create_symlink("/dev/zero", link);
    expectInputError([&] { readFile(link); }, {link, "not a regular file"});
    const std::string fifo = path("fifo.bcc");
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    expectInputError([&] { readFile(fifo); }, {fifo, "not a regular file"});
}

TEST_F(FileTest, ReadRefusesFilesOverTheSizeLimit) {
    const std::string file = path("big.txt");
    writeFileAtomic(file, std::string(2000, 'x'));
    ASSERT_EQ(::setenv("WEFT_MAX_INPUT_BYTES", "1K", 1), 0);
    expectInputError([&] { readFile(file); },
                     {file, "2.0 KB, over the input size limit of 1.0 KB", "WEFT_MAX_INPUT_BYTES"});
    ASSERT_EQ(::setenv("WEFT_MAX_INPUT_BYTES", "2000", 1), 0);
    EXPECT_EQ(readFile(file).size(), 2000u);
    ASSERT_EQ(::setenv("WEFT_MAX_INPUT_BYTES", "lots", 1), 0);
    expectInputError([&] { readFile(file); }, {"WEFT_MAX_INPUT_BYTES = \"lots\"", "suffix"});
    ::unsetenv("WEFT_MAX_INPUT_BYTES");
}

TEST_F(FileTest, OutputsThatWouldReplaceInputsAreRefused) {
    writeFileAtomic(path("scene.json"), "{}");
    fs::create_directory(path("rdm"));
    writeFileAtomic(path("rdm/meta.json"), "{}");
    const std::vector<CommandPath> inputs = {{"the scene file", path("scene.json")}};
    // Through "..", a symbolic link and a hard link: the same file each time.
    fs::create_symlink(path("scene.json"), path("link.json"));
    fs::create_hard_link(path("scene.json"), path("hard.json"));
    for (const std::string& out :
         {path("scene.json"), path("rdm/../scene.json"), path("link.json"), path("hard.json")})
        expectInputError(
            [&] {
                checkOutputsSpareInputs(inputs, {{"--out", out}});
            },
            {"--out '" + out + "' would replace the scene file", "scene.json"});
    checkOutputsSpareInputs(inputs, {{"--out", path("other.json")}, {"--png", ""}});
    // Two outputs naming one file.
    expectInputError(
        [&] {
            checkOutputsSpareInputs({}, {{"--a", path("x")}, {"--b", path("rdm/../x")}});
        },
        {"--a", "--b", "name the same file"});
    // An output file in place of a file of an input directory; a new file there is fine.
    expectInputError(
        [&] {
            checkOutputsSpareInputs({}, {{"--out", path("rdm/meta.json")}},
                                    {{"--rdm", path("rdm")}});
        },
        {"would replace a file of --rdm"});
    checkOutputsSpareInputs({}, {{"--out", path("rdm/slice.png")}}, {{"--rdm", path("rdm")}});
    // An output directory that is or holds an input.
    expectInputError(
        [&] {
            checkOutputsSpareInputs({}, {}, {{"--rdm", path("rdm")}}, {{"--out", path("rdm")}});
        },
        {"--out", "--rdm"});
    expectInputError(
        [&] {
            checkOutputsSpareInputs(inputs, {}, {}, {{"--out", dir_.string()}});
        },
        {"the scene file"});
    checkOutputsSpareInputs(inputs, {}, {{"--rdm", path("rdm")}}, {{"--out", path("new")}});
}

// All files or none: a file that cannot be written leaves the others as they were.
TEST_F(FileTest, WriteFilesAtomicIsAllOrNothing) {
    writeFileAtomic(path("a.exr"), "old a");
    fs::create_directory(path("dir.png"));  // a directory: the PNG cannot be written there
    expectInputError(
        [&] {
            writeFilesAtomic(
                {{path("a.exr"), "new a"}, {path("dir.png"), "png"}, {path("a.json"), "{}"}});
        },
        {"dir.png"});
    EXPECT_EQ(readFile(path("a.exr")), "old a");
    EXPECT_FALSE(fs::exists(path("a.json")));
    EXPECT_EQ(entries(dir_), (std::vector<std::string>{"a.exr", "dir.png"}));
    writeFilesAtomic({{path("a.exr"), "new a"}, {path("a.json"), "{}"}});
    EXPECT_EQ(readFile(path("a.exr")), "new a");
    EXPECT_EQ(readFile(path("a.json")), "{}");
}

// What a signal handler's thread removes: the temporary outputs being written now.
TEST_F(FileTest, RemoveTemporaryOutputsDeletesWhatIsBeingWritten) {
    TempDirCommit out(path("gather"));
    writeFileAtomic(out.path() + "/count.npy", "x");
    ASSERT_TRUE(fs::exists(out.path()));
    removeTemporaryOutputs();
    EXPECT_FALSE(fs::exists(out.path()));
    writeFileAtomic(path("kept.txt"), "done");  // finished files are not listed
    removeTemporaryOutputs();
    EXPECT_EQ(readFile(path("kept.txt")), "done");
}

// A file-size limit (RLIMIT_FSIZE) on this process, with SIGXFSZ ignored as
// the CLI and Python run: what is written past it fails with EFBIG.
class FileSizeLimit {
  public:
    explicit FileSizeLimit(rlim_t bytes) {
        ::getrlimit(RLIMIT_FSIZE, &saved_);
        handler_ = std::signal(SIGXFSZ, SIG_IGN);
        rlimit limit = saved_;
        limit.rlim_cur = bytes;
        ::setrlimit(RLIMIT_FSIZE, &limit);
    }
    ~FileSizeLimit() {
        ::setrlimit(RLIMIT_FSIZE, &saved_);
        std::signal(SIGXFSZ, handler_);
    }
    FileSizeLimit(const FileSizeLimit&) = delete;
    FileSizeLimit& operator=(const FileSizeLimit&) = delete;

  private:
    rlimit saved_{};
    void (*handler_)(int) = SIG_DFL;
};

// The message of the InputError that `write` throws ("" if none).
std::string inputErrorOf(const std::function<void()>& write) {
    try {
        write();
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

// Issue 41, item 1: over the file-size limit a write is an InputError saying
// "file too large", naming the file (inside an output directory by its final
// name) and the limit, and nothing is left: no temporary file or directory,
// and no file of an all-or-nothing set.
TEST_F(FileTest, OverTheFileSizeLimitIsFileTooLargeAndLeavesNothing) {
    writeFileAtomic(path("old.exr"), "old");
    const std::string big(5000, 'x');
    std::string file, dir, several, quota;
    {
        const FileSizeLimit limit(1000);  // messages are checked after, without the limit
        file = inputErrorOf([&] { writeFileAtomic(path("big.npy"), big); });
        dir = inputErrorOf([&] {
            TempDirCommit out(path("g"));
            writeFileAtomic(out.path() + "/count.npy", "fits");
            writeFileAtomic(out.path() + "/rdm_m.npy", big);
            out.commit();
        });
        several = inputErrorOf([&] {
            writeFilesAtomic({{path("old.exr"), "new"}, {path("a.png"), big}, {path("a.json"), "{}"}});
        });
    }
    EXPECT_EQ(file, "cannot write '" + path("big.npy") +
                        "': file too large: 5.0 KB, over this process's file-size limit of 1000 "
                        "bytes (ulimit -f; RLIMIT_FSIZE)");
    EXPECT_EQ(dir, "cannot write '" + path("g/rdm_m.npy") +
                       "': file too large: 5.0 KB, over this process's file-size limit of 1000 "
                       "bytes (ulimit -f; RLIMIT_FSIZE)");
    EXPECT_NE(several.find("cannot write '" + path("a.png") + "': file too large"),
              std::string::npos)
        << several;
    EXPECT_EQ(readFile(path("old.exr")), "old");
    EXPECT_EQ(entries(dir_), std::vector<std::string>{"old.exr"});
    // A quota says so; the other reasons are the system's words.
    EXPECT_EQ(writeErrorText(EDQUOT, 5000),
              "file too large for the disk quota: 5.0 KB, over what this user may still write "
              "there (Disk quota exceeded)");
    EXPECT_EQ(writeErrorText(ENOSPC, 5000), "No space left on device");
}

// Issue 41, item 5: the clean-up on signals against writers that keep
// creating, renaming and committing. In a child process (a death test,
// forked), the clean-up is set up as the CLI does it; two threads write files
// into output directories (5 files, then a commit that replaces the previous
// round's directory) and files beside them, and a third sends the process
// `signal` after `delay`. The process must die of the signal and leave only
// complete outputs: no DIR.tmp.<pid>/, no .NAME.tmp.*, no DIR.old.<pid>/, and
// every DIR holding its 5 files.
void writeUntilSignalled(const std::string& dir, int signal, std::chrono::microseconds delay) {
    removeTemporaryOutputsOnSignals();
    std::thread([signal, delay] {
        std::this_thread::sleep_for(delay);
        ::kill(::getpid(), signal);
    }).detach();
    auto writer = [&dir](int id) {
        try {
            for (;;) {
                TempDirCommit out(dir + "/g" + std::to_string(id));
                for (int k = 0; k < 5; ++k)
                    writeFileAtomic(out.path() + "/" + std::to_string(k) + ".npy", "x");
                writeFileAtomic(dir + "/f" + std::to_string(id), "y");
                out.commit();
            }
        } catch (...) {
            // Only the signal may end this process; a writer that fails waits for it.
        }
        for (;;) ::pause();
    };
    std::thread second(writer, 1);
    writer(0);
}

// Before, about half of these runs left a temporary: the clean-up's removal of
// DIR.tmp.<pid>/ failed (ENOTEMPTY) when a writer created a file in it
// meanwhile, or it ran between a commit's two renames (DIR.old.<pid>/), or
// between a file's creation and its listing (.NAME.tmp.*).
TEST_F(FileTest, SignalsAtAnyMomentOfWritingLeaveNoTemporaryOutput) {
    const auto start = std::chrono::steady_clock::now();
    const int runs = 40;
    int spoilt = 0;
    // Delays from 0 to 58.5 ms: the set-up, the first files, commits, later rounds.
    for (int k = 0; k < runs; ++k) {
        const int signal = (k % 3 == 0) ? SIGINT : (k % 3 == 1) ? SIGHUP : SIGTERM;
        const std::chrono::microseconds delay(k * 1500);
        const std::string run = path("run" + std::to_string(k));
        fs::create_directory(run);
        EXPECT_EXIT(writeUntilSignalled(run, signal, delay), ::testing::KilledBySignal(signal), "");
        bool whole = true;
        for (const std::string& name : entries(run)) {
            const bool output = name == "g0" || name == "g1" || name == "f0" || name == "f1";
            const bool partial = output && name[0] == 'g' && entries(run + "/" + name).size() != 5;
            EXPECT_TRUE(output && !partial) << "signal " << signal << " after " << delay.count()
                                            << " us left " << name << (partial ? " partial" : "");
            whole = whole && output && !partial;
        }
        spoilt += !whole;
    }
    EXPECT_EQ(spoilt, 0) << "of " << runs << " runs left a temporary or partial output";
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(60));
}

TEST_F(FileTest, ConcurrentWritersNeverTearTheFile) {
    const std::string p = path("shared.txt");
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t) {
        threads.emplace_back([&, t] {
            const std::string content(10000 + t, static_cast<char>('a' + t));
            for (int i = 0; i < 20; ++i) writeFileAtomic(p, content);
        });
    }
    for (std::thread& th : threads) th.join();
    const std::string final = readFile(p);
    ASSERT_GE(final.size(), 10000u);
    const size_t t = final.size() - 10000;
    ASSERT_LT(t, 4u);
    EXPECT_EQ(final, std::string(10000 + t, static_cast<char>('a' + t)));
    EXPECT_EQ(entries(dir_), std::vector<std::string>{"shared.txt"});
}

TEST_F(FileTest, TempDirCommitCreatesFinalDirectory) {
    const std::string finalPath = path("out");
    {
        TempDirCommit out(finalPath);
        EXPECT_EQ(out.path(), finalPath + ".tmp." + std::to_string(::getpid()));
        EXPECT_EQ(out.finalPath(), finalPath);
        EXPECT_TRUE(fs::is_directory(out.path()));
        EXPECT_FALSE(fs::exists(finalPath));
        writeFileAtomic(out.path() + "/a.txt", "A");
        EXPECT_FALSE(out.committed());
        out.commit();
        EXPECT_TRUE(out.committed());
        expectInputError([&] { out.commit(); }, {finalPath, "already committed"});
    }
    EXPECT_EQ(readFile(finalPath + "/a.txt"), "A");
    EXPECT_EQ(entries(dir_), std::vector<std::string>{"out"});
}

TEST_F(FileTest, TempDirCommitReplacesExistingDirectory) {
    const std::string finalPath = path("out");
    fs::create_directories(finalPath + "/nested");
    writeFileAtomic(finalPath + "/old.txt", "old");
    writeFileAtomic(finalPath + "/nested/deep.txt", "old");
    {
        TempDirCommit out(finalPath + "/");  // a trailing slash is fine
        EXPECT_EQ(out.finalPath(), finalPath);
        writeFileAtomic(out.path() + "/new.txt", "new");
        // Until commit, the old directory is untouched.
        EXPECT_EQ(readFile(finalPath + "/old.txt"), "old");
        out.commit();
    }
    EXPECT_EQ(entries(finalPath), std::vector<std::string>{"new.txt"});
    EXPECT_EQ(entries(dir_), std::vector<std::string>{"out"});
}

TEST_F(FileTest, TempDirCommitCleansUpWithoutCommit) {
    const std::string finalPath = path("out");
    std::string tempPath;
    try {
        TempDirCommit out(finalPath);
        tempPath = out.path();
        fs::create_directories(tempPath + "/a/b");
        writeFileAtomic(tempPath + "/a/b/c.txt", "partial");
        throw std::runtime_error("render failed");
    } catch (const std::runtime_error&) {
    }
    EXPECT_FALSE(fs::exists(tempPath));
    EXPECT_FALSE(fs::exists(finalPath));
    EXPECT_EQ(entries(dir_), std::vector<std::string>{});

    // A stale temporary directory from an earlier run is replaced.
    fs::create_directories(tempPath + "/stale");
    {
        TempDirCommit out(finalPath);
        EXPECT_EQ(entries(out.path()), std::vector<std::string>{});
    }
}

TEST_F(FileTest, TempDirCommitErrorsNamePath) {
    const std::string noParent = path("missing/out");
    expectInputError([&] { TempDirCommit out(noParent); }, {noParent, "No such file"});
    expectInputError([&] { TempDirCommit out(""); }, {"invalid output directory"});

    const std::string notDir = path("file.txt");
    writeFileAtomic(notDir, "x");
    // Refused at construction, before any work is done, and nothing is created.
    expectInputError([&] { TempDirCommit out(notDir); }, {notDir, "not a directory"});
    EXPECT_EQ(readFile(notDir), "x");
    EXPECT_FALSE(std::filesystem::exists(notDir + ".tmp." + std::to_string(::getpid())));
}

// What a model records of its gather folder (docs/model-format.md, "fit").
TEST(RecordedPath, NeverAnAbsolutePathOfThisMachine) {
    const std::string base = "/srv/weft";
    // Relative: as given, normalised.
    EXPECT_EQ(recordedPath("cotton-rdm", base), "cotton-rdm");
    EXPECT_EQ(recordedPath("./g16/cotton/", base), "g16/cotton");
    EXPECT_EQ(recordedPath("a/../b", base), "b");
    EXPECT_EQ(recordedPath("../g16/cotton", base), "../g16/cotton");
    // Absolute inside the current directory: relative to it.
    EXPECT_EQ(recordedPath("/srv/weft/build/g16/cotton", base), "build/g16/cotton");
    EXPECT_EQ(recordedPath("/srv/weft/./rdm/", base), "rdm");
    // Absolute elsewhere: the folder's name alone.
    EXPECT_EQ(recordedPath("/data/g16/cotton", base), "cotton");
    EXPECT_EQ(recordedPath("/data/fa/", base), "fa");
    EXPECT_EQ(recordedPath("/srv/weftly/rdm", base), "rdm");  // not inside /srv/weft
    EXPECT_EQ(recordedPath("/srv/weft/../other/rdm", base), "rdm");
    // The one-argument form is relative to the current directory.
    EXPECT_EQ(recordedPath((fs::current_path() / "x" / "rdm").string()), "x/rdm");
    EXPECT_EQ(recordedPath("rdm"), "rdm");
}

}  // namespace
}  // namespace weft
