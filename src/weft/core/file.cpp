#include "weft/core/file.h"

#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <mutex>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/limits.h"

namespace weft {

std::string lowercaseExtension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

namespace {

// `p` relative to `base` if it lies inside it ("." for `base` itself), else empty.
std::filesystem::path insideOf(const std::filesystem::path& p, const std::filesystem::path& base) {
    const std::filesystem::path rel = p.lexically_relative(base.lexically_normal());
    return !rel.empty() && *rel.begin() != ".." ? rel : std::filesystem::path();
}

}  // namespace

std::string recordedPath(const std::string& path, const std::string& base) {
    namespace fs = std::filesystem;
    fs::path p = fs::path(path).lexically_normal();
    if (!p.empty() && p.filename().empty()) p = p.parent_path();  // "rdm/" -> "rdm"
    if (p.is_relative()) return p.empty() ? path : p.string();
    if (const fs::path inside = insideOf(p, base); !inside.empty()) return inside.string();
    return p.filename().string();  // "" for "/"
}

std::string recordedPath(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::path cwd = fs::current_path(ec);  // links resolved
    if (ec || fs::path(path).is_relative()) return recordedPath(path, cwd.string());
    // Inside the current directory through a link in `path` ("/tmp" -> "/private/tmp").
    const fs::path resolved = fs::weakly_canonical(path, ec);
    if (!ec && insideOf(fs::path(path).lexically_normal(), cwd).empty())
        if (const fs::path inside = insideOf(resolved, cwd); !inside.empty()) return inside.string();
    return recordedPath(path, cwd.string());
}

std::string writeErrorText(int err, uint64_t bytes) {
    const std::string size = bytes > 0 ? byteText(static_cast<double>(bytes)) + ", " : "";
    if (err == EFBIG) {
        struct rlimit limit {};
        if (::getrlimit(RLIMIT_FSIZE, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
            return "file too large: " + size + "over this process's file-size limit of " +
                   std::to_string(limit.rlim_cur) + " bytes (ulimit -f; RLIMIT_FSIZE)";
        return "file too large: " + size + "over what the file system takes in one file";
    }
    if (err == EDQUOT)
        return "file too large for the disk quota: " + size +
               "over what this user may still write there (" + std::strerror(err) + ")";
    return std::strerror(err);
}

namespace {

[[noreturn]] void fail(const std::string& what, const std::string& path, int err) {
    throw InputError(what + " '" + path + "': " + std::strerror(err));
}

// Splits "a/b/c.npy" into ("a/b/", "c.npy"); "c.npy" into ("", "c.npy").
std::pair<std::string, std::string> splitPath(const std::string& path) {
    const size_t slash = path.find_last_of('/');
    if (slash == std::string::npos) return {"", path};
    return {path.substr(0, slash + 1), path.substr(slash + 1)};
}

// Process-wide counter so concurrent writers in one process never share a
// temporary name.
std::atomic<uint64_t> tempCounter{0};

// The temporary outputs that exist now, and the lock that orders every change
// to their directory entries against the clean-up on signals (core/file.h).
struct TemporaryOutputs {
    std::mutex mutex;
    std::map<std::string, bool> isDirectory;
};
TemporaryOutputs& temporaryOutputs() {
    // Never destroyed: the clean-up thread may take it while exit() runs the
    // static destructors.
    static TemporaryOutputs* const registry = new TemporaryOutputs;
    return *registry;
}
using RegistryLock = std::unique_lock<std::mutex>;
RegistryLock lockTemporaries() { return RegistryLock(temporaryOutputs().mutex); }
// Both with the lock held (the argument is its proof).
void listTemporary(const RegistryLock&, const std::string& path, bool isDirectory) {
    temporaryOutputs().isDirectory[path] = isDirectory;
}
void unlistTemporary(const RegistryLock&, const std::string& path) {
    temporaryOutputs().isDirectory.erase(path);
}

// `path` as the user will know it: a file inside a TempDirCommit's
// DIR.tmp.<pid>/ by its name in DIR/ ("g.tmp.42/rdm_m.npy" -> "g/rdm_m.npy").
std::string finalName(const std::string& path) {
    const RegistryLock lock = lockTemporaries();
    for (const auto& [temp, isDirectory] : temporaryOutputs().isDirectory)
        if (isDirectory && path.size() > temp.size() && path[temp.size()] == '/' &&
            path.compare(0, temp.size(), temp) == 0)
            return temp.substr(0, temp.rfind(".tmp.")) + path.substr(temp.size());
    return path;
}

// Writing the `bytes` bytes of `path` failed: InputError naming the file as
// the user will find it (finalName).
[[noreturn]] void failWrite(const std::string& path, int err, size_t bytes) {
    throw InputError("cannot write '" + finalName(path) + "': " + writeErrorText(err, bytes));
}

// Closes fd (if open), unlinks and unlists the temporary file; keeps errno intact.
void discardTemp(int fd, const std::string& tempPath) {
    const int saved = errno;
    if (fd >= 0) ::close(fd);
    {
        const RegistryLock lock = lockTemporaries();
        ::unlink(tempPath.c_str());
        unlistTemporary(lock, tempPath);
    }
    errno = saved;
}

// Removes the file or directory `path`, whatever is removed beside it
// meanwhile; the clean-up's removal.
void removeTemporary(const std::string& path, bool isDirectory) {
    if (!isDirectory) {
        ::unlink(path.c_str());
        return;
    }
    // With the lock held nothing is created in `path` any more, so one pass
    // removes it; the retries only bound what a writer outside the registry
    // (a test making sub-directories) could add.
    std::error_code ec;
    for (int attempt = 0; attempt < 100; ++attempt) {
        std::filesystem::remove_all(path, ec);
        if (!std::filesystem::exists(std::filesystem::symlink_status(path, ec))) return;
    }
}

std::string stripTrailingSlashes(std::string p) {
    while (p.size() > 1 && p.back() == '/') p.pop_back();
    return p;
}

}  // namespace

namespace {

// Writes `bytes` to a new temporary sibling of `path` (listed until renamed or
// removed) and returns its name; InputError naming `path` on failure.
std::string writeTemporarySibling(const std::string& path, std::string_view bytes) {
    if (path.empty()) throw InputError("cannot write a file with an empty path");
    const auto [dir, base] = splitPath(path);
    if (base.empty()) throw InputError("cannot write '" + path + "': the path names a directory");
    const std::string tempPath = dir + "." + base + ".tmp." + std::to_string(::getpid()) + "." +
                                 std::to_string(tempCounter.fetch_add(1));

    int fd = -1;
    {
        // Created and listed at once (core/file.h, clean-up on signals).
        const RegistryLock lock = lockTemporaries();
        fd = ::open(tempPath.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd < 0) fail("cannot write", path, errno);
        listTemporary(lock, tempPath, false);
    }

    // A write over the file-size limit (RLIMIT_FSIZE) fails with EFBIG where
    // SIGXFSZ is ignored (the CLI does, src/cmd/main.cpp; so does Python);
    // otherwise the kernel's SIGXFSZ ends the process here.
    size_t done = 0;
    while (done < bytes.size()) {
        const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
        if (n < 0) {
            if (errno == EINTR) continue;
            const int err = errno;
            discardTemp(fd, tempPath);
            failWrite(path, err, bytes.size());
        }
        done += static_cast<size_t>(n);
    }
    // fsync before rename: otherwise a crash can leave the new name pointing
    // at an empty file on some file systems.
    if (::fsync(fd) != 0 && errno != EINVAL && errno != EROFS) {
        const int err = errno;
        discardTemp(fd, tempPath);
        failWrite(path, err, bytes.size());
    }
    if (::close(fd) != 0) {
        const int err = errno;
        discardTemp(-1, tempPath);
        failWrite(path, err, bytes.size());
    }
    return tempPath;
}

// Renames the temporary file into place and unlists it; the caller holds the lock.
void renameTemporary(const RegistryLock& lock, const std::string& tempPath,
                     const std::string& path) {
    if (::rename(tempPath.c_str(), path.c_str()) != 0) {
        const int err = errno;
        ::unlink(tempPath.c_str());
        unlistTemporary(lock, tempPath);
        fail("cannot write", path, err);
    }
    unlistTemporary(lock, tempPath);
}

}  // namespace

void writeFileAtomic(const std::string& path, std::string_view bytes) {
    const std::string tempPath = writeTemporarySibling(path, bytes);
    const RegistryLock lock = lockTemporaries();
    renameTemporary(lock, tempPath, path);
}

void writeFilesAtomic(const std::vector<std::pair<std::string, std::string>>& files) {
    // What would make a rename fail after the others: refused before any is written.
    for (const auto& [path, bytes] : files) {
        std::error_code ec;
        if (std::filesystem::is_directory(path, ec))
            throw InputError("cannot write '" + path + "': it is a directory");
    }
    std::vector<std::string> temps;
    try {
        for (const auto& [path, bytes] : files) temps.push_back(writeTemporarySibling(path, bytes));
    } catch (...) {
        for (const std::string& t : temps) discardTemp(-1, t);
        throw;
    }
    // Every file is complete on disk: the renames are all that is left, under
    // one hold of the lock, so that a signal sees all of them or none done.
    const RegistryLock lock = lockTemporaries();
    for (size_t k = 0; k < files.size(); ++k) {
        try {
            renameTemporary(lock, temps[k], files[k].first);
        } catch (...) {
            for (size_t j = k + 1; j < temps.size(); ++j) {
                ::unlink(temps[j].c_str());
                unlistTemporary(lock, temps[j]);
            }
            throw;
        }
    }
}

namespace {

std::filesystem::path resolved(const std::string& path) {
    std::error_code ec;
    std::filesystem::path p = std::filesystem::weakly_canonical(path, ec);
    if (ec) p = std::filesystem::absolute(path, ec).lexically_normal();
    return p;
}

bool sameFile(const std::filesystem::path& a, const std::filesystem::path& b) {
    if (a == b) return true;
    std::error_code ec;
    return std::filesystem::equivalent(a, b, ec) && !ec;
}

// `inner` is `outer` or lies below it.
bool within(const std::filesystem::path& inner, const std::filesystem::path& outer) {
    auto o = outer.begin(), i = inner.begin();
    for (; o != outer.end(); ++o, ++i)
        if (i == inner.end() || *i != *o) return false;
    return true;
}

[[noreturn]] void refuseOverwrite(const CommandPath& output, const CommandPath& input,
                                  const char* how) {
    throw InputError(output.role + " '" + output.path + "' would " + how + " " + input.role + " '" +
                     input.path + "', an input of the same command: choose another " +
                     "output path");
}

}  // namespace

void checkOutputsSpareInputs(const std::vector<CommandPath>& inputFiles,
                             const std::vector<CommandPath>& outputFiles,
                             const std::vector<CommandPath>& inputDirs,
                             const std::vector<CommandPath>& outputDirs) {
    for (size_t k = 0; k < outputFiles.size(); ++k) {
        const CommandPath& out = outputFiles[k];
        if (out.path.empty()) continue;
        const std::filesystem::path o = resolved(out.path);
        for (size_t j = 0; j < k; ++j)
            if (!outputFiles[j].path.empty() && sameFile(o, resolved(outputFiles[j].path)))
                throw InputError(outputFiles[j].role + " '" + outputFiles[j].path + "' and " +
                                 out.role + " '" + out.path + "' name the same file");
        for (const CommandPath& in : inputFiles)
            if (!in.path.empty() && sameFile(o, resolved(in.path)))
                refuseOverwrite(out, in, "replace");
        for (const CommandPath& in : inputDirs) {
            if (in.path.empty()) continue;
            const std::filesystem::path d = resolved(in.path);
            std::error_code ec;
            if (sameFile(o, d) || (within(o, d) && std::filesystem::exists(o, ec)))
                refuseOverwrite(out, in, "replace a file of");
        }
    }
    for (const CommandPath& out : outputDirs) {
        if (out.path.empty()) continue;
        const std::filesystem::path o = resolved(out.path);
        for (const auto* inputs : {&inputFiles, &inputDirs})
            for (const CommandPath& in : *inputs)
                if (!in.path.empty() &&
                    (within(resolved(in.path), o) || sameFile(o, resolved(in.path))))
                    refuseOverwrite(out, in, "replace (as a directory written whole)");
    }
}

bool sameFilePath(const std::string& a, const std::string& b) {
    return !a.empty() && !b.empty() && sameFile(resolved(a), resolved(b));
}

void removeTemporaryOutputs() {
    const RegistryLock lock = lockTemporaries();
    for (const auto& [path, isDirectory] : temporaryOutputs().isDirectory)
        removeTemporary(path, isDirectory);
    temporaryOutputs().isDirectory.clear();
}

namespace {

// StopOnSignal's state: how many live, their message, the signal received.
struct StopState {
    std::mutex mutex;
    int armed = 0;
    std::string what;
};
StopState& stopState() {
    static StopState* const state = new StopState;  // never destroyed, as the registry
    return *state;
}
std::atomic<int> stopSignal{0};

// A first SIGINT or SIGTERM while a StopOnSignal lives: recorded and announced.
bool recordStop(int received) {
    if (received == SIGHUP || stopSignal.load() != 0) return false;
    const std::lock_guard<std::mutex> lock(stopState().mutex);
    if (stopState().armed == 0) return false;
    stopSignal.store(received);
    std::fprintf(stderr, "\nweft: %s: stopping; %s will be written (%s again: quit without)\n",
                 received == SIGINT ? "SIGINT" : "SIGTERM", stopState().what.c_str(),
                 received == SIGINT ? "Ctrl-C" : "SIGTERM");
    return true;
}

}  // namespace

StopOnSignal::StopOnSignal(std::string what) {
    const std::lock_guard<std::mutex> lock(stopState().mutex);
    ++stopState().armed;
    stopState().what = std::move(what);
}

StopOnSignal::~StopOnSignal() {
    const std::lock_guard<std::mutex> lock(stopState().mutex);
    --stopState().armed;
}

int StopOnSignal::signal() { return stopSignal.load(); }

void checkOutputsWritable(const std::vector<CommandPath>& outputFiles) {
    for (const CommandPath& out : outputFiles) {
        if (out.path.empty()) continue;
        try {
            std::error_code ec;
            if (std::filesystem::is_directory(out.path, ec))
                throw InputError("cannot write '" + out.path + "': it is a directory");
            discardTemp(-1, writeTemporarySibling(out.path, ""));
        } catch (const InputError& e) {
            throw InputError(out.role + ": " + e.what());
        }
    }
}

void removeTemporaryOutputsOnSignals() {
    sigset_t signals;
    sigemptyset(&signals);
    for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&signals, s);
    if (pthread_sigmask(SIG_BLOCK, &signals, nullptr) != 0) return;
    std::thread([signals] {
        int received = 0;
        do {
            if (sigwait(&signals, &received) != 0) return;
        } while (recordStop(received));
        // Taken for good: no writer creates, renames or lists a temporary
        // output from now on, so what is removed here stays removed.
        temporaryOutputs().mutex.lock();
        for (const auto& [path, isDirectory] : temporaryOutputs().isDirectory)
            removeTemporary(path, isDirectory);
        std::signal(received, SIG_DFL);
        pthread_sigmask(SIG_UNBLOCK, &signals, nullptr);  // this thread only
        std::raise(received);
        ::_exit(128 + received);  // not reached: the default action ends the process
    }).detach();
}

std::string readFile(const std::string& path) {
    // O_NONBLOCK: opening a FIFO without a writer must not block (it is refused below).
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) fail("cannot read", path, errno);
    struct stat st {};
    if (::fstat(fd, &st) != 0) {
        const int err = errno;
        ::close(fd);
        fail("cannot read", path, err);
    }
    if (S_ISDIR(st.st_mode)) {
        ::close(fd);
        fail("cannot read", path, EISDIR);
    }
    // A device or FIFO (a link to /dev/zero) could be endless: regular files only.
    if (!S_ISREG(st.st_mode)) {
        ::close(fd);
        throw InputError("cannot read '" + path +
                         "': not a regular file (a device, FIFO or socket); weft reads regular "
                         "files only");
    }
    const uint64_t limit = maxInputBytes();
    if (static_cast<uint64_t>(st.st_size) > limit) {
        ::close(fd);
        throw InputError("cannot read '" + path +
                         "': " + byteText(static_cast<double>(st.st_size)) +
                         ", over the input size limit of " + byteText(static_cast<double>(limit)) +
                         " (set WEFT_MAX_INPUT_BYTES to change it; docs/limits.md)");
    }
    std::string out;
    out.reserve(static_cast<size_t>(st.st_size));
    char buf[1 << 16];
    for (;;) {
        const ssize_t n = ::read(fd, buf, sizeof buf);
        if (n < 0) {
            if (errno == EINTR) continue;
            const int err = errno;
            ::close(fd);
            fail("cannot read", path, err);
        }
        if (n == 0) break;
        // The file may grow while it is read: keep the bound.
        if (out.size() + static_cast<size_t>(n) > limit) {
            ::close(fd);
            throw InputError("cannot read '" + path + "': it grew past the input size limit of " +
                             byteText(static_cast<double>(limit)) + " while being read");
        }
        out.append(buf, static_cast<size_t>(n));
    }
    ::close(fd);
    return out;
}

TempDirCommit::TempDirCommit(std::string finalPath)
    : finalPath_(stripTrailingSlashes(std::move(finalPath))) {
    if (finalPath_.empty() || finalPath_ == "/" || finalPath_ == "." || finalPath_ == "..")
        throw InputError("invalid output directory '" + finalPath_ +
                         "': expected a path naming a new or replaceable directory");
    {
        // Refuse at once what commit() would refuse after the work is done.
        std::error_code ec;
        const auto st = std::filesystem::symlink_status(finalPath_, ec);
        if (std::filesystem::exists(st) && !std::filesystem::is_directory(st))
            throw InputError("cannot write output directory '" + finalPath_ +
                             "': it exists and is not a directory");
    }
    tempPath_ = finalPath_ + ".tmp." + std::to_string(::getpid());
    // A leftover from an earlier process with the same pid is stale: remove it.
    std::error_code ec;
    std::filesystem::remove_all(tempPath_, ec);
    if (ec) throw InputError("cannot remove stale directory '" + tempPath_ + "': " + ec.message());
    const RegistryLock lock = lockTemporaries();  // made and listed at once
    if (::mkdir(tempPath_.c_str(), 0777) != 0) fail("cannot create directory", tempPath_, errno);
    listTemporary(lock, tempPath_, true);
}

TempDirCommit::~TempDirCommit() {
    if (committed_) return;
    const RegistryLock lock = lockTemporaries();
    std::error_code ec;  // Never throw from a destructor; a leftover is harmless.
    std::filesystem::remove_all(tempPath_, ec);
    unlistTemporary(lock, tempPath_);
}

void TempDirCommit::commit() {
    if (committed_) throw InputError("output directory '" + finalPath_ + "' already committed");
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::file_status st = fs::symlink_status(finalPath_, ec);
    const bool exists = fs::exists(st);
    if (exists && !fs::is_directory(st))
        throw InputError("cannot replace '" + finalPath_ + "': it exists and is not a directory");

    std::string oldPath;
    // Under the lock to the end: a signal sees the old directory in place and
    // the new one temporary, or the new one in place and no old copy; never
    // the old one moved aside.
    const RegistryLock lock = lockTemporaries();
    if (exists) {
        // Move the old directory aside rather than deleting it first, so that
        // a failed rename below can put it back.
        oldPath = finalPath_ + ".old." + std::to_string(::getpid());
        fs::remove_all(oldPath, ec);
        if (::rename(finalPath_.c_str(), oldPath.c_str()) != 0)
            fail("cannot replace directory", finalPath_, errno);
    }
    if (::rename(tempPath_.c_str(), finalPath_.c_str()) != 0) {
        const int err = errno;
        if (!oldPath.empty()) ::rename(oldPath.c_str(), finalPath_.c_str());
        fail("cannot rename '" + tempPath_ + "' to", finalPath_, err);
    }
    unlistTemporary(lock, tempPath_);
    committed_ = true;
    if (!oldPath.empty()) {
        fs::remove_all(oldPath, ec);
        if (ec)
            throw InputError("wrote '" + finalPath_ + "' but cannot remove the old copy '" +
                             oldPath + "': " + ec.message());
    }
}

}  // namespace weft
