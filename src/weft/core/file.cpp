#include "weft/core/file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <system_error>

#include "weft/core/error.h"

namespace weft {

std::string lowercaseExtension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

namespace {

std::string errnoText(int err) { return std::strerror(err); }

[[noreturn]] void fail(const std::string& what, const std::string& path, int err) {
    throw InputError(what + " '" + path + "': " + errnoText(err));
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

// Closes fd (if open) and unlinks the temporary file; keeps errno intact.
void discardTemp(int fd, const std::string& tempPath) {
    const int saved = errno;
    if (fd >= 0) ::close(fd);
    ::unlink(tempPath.c_str());
    errno = saved;
}

std::string stripTrailingSlashes(std::string p) {
    while (p.size() > 1 && p.back() == '/') p.pop_back();
    return p;
}

}  // namespace

void writeFileAtomic(const std::string& path, std::string_view bytes) {
    if (path.empty()) throw InputError("cannot write a file with an empty path");
    const auto [dir, base] = splitPath(path);
    if (base.empty()) throw InputError("cannot write '" + path + "': the path names a directory");
    const std::string tempPath = dir + "." + base + ".tmp." + std::to_string(::getpid()) + "." +
                                 std::to_string(tempCounter.fetch_add(1));

    const int fd = ::open(tempPath.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0) fail("cannot write", path, errno);

    size_t done = 0;
    while (done < bytes.size()) {
        const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
        if (n < 0) {
            if (errno == EINTR) continue;
            const int err = errno;
            discardTemp(fd, tempPath);
            fail("cannot write", path, err);
        }
        done += static_cast<size_t>(n);
    }
    // fsync before rename: otherwise a crash can leave the new name pointing
    // at an empty file on some file systems.
    if (::fsync(fd) != 0 && errno != EINVAL && errno != EROFS) {
        const int err = errno;
        discardTemp(fd, tempPath);
        fail("cannot write", path, err);
    }
    if (::close(fd) != 0) {
        const int err = errno;
        discardTemp(-1, tempPath);
        fail("cannot write", path, err);
    }
    if (::rename(tempPath.c_str(), path.c_str()) != 0) {
        const int err = errno;
        discardTemp(-1, tempPath);
        fail("cannot write", path, err);
    }
}

std::string readFile(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
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
    std::string out;
    if (S_ISREG(st.st_mode) && st.st_size > 0) out.reserve(static_cast<size_t>(st.st_size));
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
    if (::mkdir(tempPath_.c_str(), 0777) != 0) fail("cannot create directory", tempPath_, errno);
}

TempDirCommit::~TempDirCommit() {
    if (committed_) return;
    std::error_code ec;  // Never throw from a destructor; a leftover is harmless.
    std::filesystem::remove_all(tempPath_, ec);
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
    committed_ = true;
    if (!oldPath.empty()) {
        fs::remove_all(oldPath, ec);
        if (ec)
            throw InputError("wrote '" + finalPath_ + "' but cannot remove the old copy '" +
                             oldPath + "': " + ec.message());
    }
}

}  // namespace weft
