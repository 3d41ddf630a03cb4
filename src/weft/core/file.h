// weft/core/file.h — whole-file reads and crash-safe writes.
//
// Every output file weft writes goes through writeFileAtomic: the bytes land in
// a temporary sibling file which is then renamed over the target, so a reader
// (or a crash) sees either the old file or the complete new one, never a torn
// one. TempDirCommit does the same for a whole output directory. Every failure
// throws InputError naming the path and the system's reason (strerror); a file
// over the file-size limit (RLIMIT_FSIZE, `ulimit -f`: EFBIG) or a disk quota
// (EDQUOT) says "file too large" with the size and the limit (writeErrorText).
//
// Clean-up on signals (removeTemporaryOutputsOnSignals). The temporary outputs
// that exist now are listed in a registry, guarded by one lock. Every change to
// the directory entries of a listed output happens under that lock: creating a
// temporary file or directory together with listing it, renaming a file into
// place together with unlisting it, removing one, and TempDirCommit::commit's
// renames. The clean-up takes the lock and keeps it until the process has died
// of the signal. So when it removes a temporary directory, no writer can create
// a file inside it behind its back (which made the removal fail with ENOTEMPTY
// and left DIR.tmp.<pid>/), no temporary exists unlisted (created, not yet
// listed), and a commit is seen either not begun or finished (the clean-up
// waits for the removal of the directory it replaces). A writer that comes to
// the lock afterwards waits there until the process ends. Writing the bytes of
// an open temporary file needs no lock: it adds no entry. The clean-up runs in
// an ordinary thread woken by sigwait, not in an asynchronous signal handler,
// so taking a mutex and allocating there are safe.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace weft {

// Writes `bytes` to `path` atomically: writes and fsyncs a temporary file
// `<dir>/.<basename>.tmp.<pid>.<counter>` and renames it over `path`. On failure
// the temporary file is removed and InputError names `path` and the reason
// (missing or unwritable directory, disk full, over the file-size limit or a
// disk quota, `path` is a directory...).
void writeFileAtomic(const std::string& path, std::string_view bytes);

// Several files that belong together (an image, its PNG and its statistics):
// each (path, bytes) is first written to its temporary sibling, then all are
// renamed into place, so a failure while writing leaves every target as it
// was. (A failure of a rename itself, which writing first makes unlikely,
// leaves the earlier files replaced.)
void writeFilesAtomic(const std::vector<std::pair<std::string, std::string>>& files);

// Deletes every temporary file or directory that writeFileAtomic,
// writeFilesAtomic or TempDirCommit is writing now, and forgets them (the
// writers' later removals or renames of them then fail harmlessly). For tests;
// a program uses removeTemporaryOutputsOnSignals.
void removeTemporaryOutputs();

// The clean-up on signals of a command-line program (src/cmd/main.cpp): blocks
// SIGINT, SIGTERM and SIGHUP in the calling thread and starts a thread that
// waits for one of them (sigwait), takes the registry's lock for good (see the
// top of this file), deletes every temporary output being written and ends
// the process by the same signal (the exit status a shell expects: 130 for
// Ctrl-C). Call it first thing in main(), before any other thread exists, so
// that every thread (TBB's workers too) inherits the blocked mask. Not for a
// library inside another program (the Python module): it takes those signals
// from the host.
void removeTemporaryOutputsOnSignals();

// A command that can stop early and keep its work (weft render): while a
// StopOnSignal lives, the first SIGINT or SIGTERM that the clean-up thread
// above receives does not end the process but is recorded (signal()) and
// announced on stderr; the command finishes what is in flight, writes its
// outputs and exits 128 + signal(). A second SIGINT or SIGTERM, or a SIGHUP,
// takes the clean-up path at once. Without removeTemporaryOutputsOnSignals
// (the Python module) nothing receives the signals: signal() stays 0.
class StopOnSignal {
  public:
    // `what`: what the stop keeps, for the message ("the samples traced so far").
    explicit StopOnSignal(std::string what);
    ~StopOnSignal();
    StopOnSignal(const StopOnSignal&) = delete;
    StopOnSignal& operator=(const StopOnSignal&) = delete;
    // 0, or the signal that asked to stop.
    static int signal();
};

// Why a write failed, for a message after "cannot write 'PATH': ": for EFBIG
// "file too large: SIZE, over this process's file-size limit of N bytes (ulimit
// -f; RLIMIT_FSIZE)" (or "... over what the file system takes in one file"
// without a limit), for EDQUOT "file too large for the disk quota ...", else
// strerror(err). `bytes` is the size being written, 0 if unknown.
std::string writeErrorText(int err, uint64_t bytes = 0);

// A path a command reads or writes, and what it is in messages ("--in", "the
// scene's yarns[0].curves", "--out's PNG").
struct CommandPath {
    std::string role, path;
};
// No output of a command may replace one of its inputs: InputError naming both
// when an output file is an input file, or an output directory (written
// whole, replacing what was there) is or holds an input, or an output file
// lies in an input directory in place of one of its files; nor may two output
// files be the same. Paths compare
// after resolving links, "." and ".." (and existing files by identity, so a
// hard link counts). Empty paths are skipped.
void checkOutputsSpareInputs(const std::vector<CommandPath>& inputFiles,
                             const std::vector<CommandPath>& outputFiles,
                             const std::vector<CommandPath>& inputDirs = {},
                             const std::vector<CommandPath>& outputDirs = {});

// Whether two paths name the same file, compared as checkOutputsSpareInputs does.
bool sameFilePath(const std::string& a, const std::string& b);

// Before long work: every output file can be written now. InputError naming
// the role and the path otherwise (its directory missing or not writable, or
// the path a directory); a probe file is created beside each and removed.
void checkOutputsWritable(const std::vector<CommandPath>& outputFiles);

// The extension of `path` with its dot, in lower case ("a/B.EXR" -> ".exr"; "" if none),
// for picking a reader by file type.
std::string lowercaseExtension(const std::string& path);

// `path` as an output that may be committed or shared records it (the gather
// folder in a model's fit record): never an absolute path of this machine. A
// relative path is kept as given, lexically normalised ("./rdm/" -> "rdm"); an
// absolute one becomes relative to `base` (the current directory) when it lies
// inside it, and is otherwise reduced to its final component
// ("/data/g16/cotton" -> "cotton"). docs/model-format.md, "fit".
std::string recordedPath(const std::string& path, const std::string& base);
std::string recordedPath(const std::string& path);

// The whole file as bytes; InputError naming `path` if it is missing, a
// directory, not a regular file (a device or FIFO), larger than
// maxInputBytes() (core/limits.h) or unreadable.
std::string readFile(const std::string& path);

// RAII helper for writing a whole output directory atomically.
//
//     TempDirCommit out("renders/run1");       // creates renders/run1.tmp.<pid>
//     writeFileAtomic(out.path() + "/a.npy", ...);
//     out.commit();                            // renames it to renders/run1
//
// commit() replaces an existing directory of the final name (the old one is
// first moved aside, then deleted once the new one is in place). If commit()
// is never called (e.g. an exception unwinds), the destructor deletes the
// temporary directory. Errors are InputError naming the path.
class TempDirCommit {
  public:
    explicit TempDirCommit(std::string finalPath);
    ~TempDirCommit();
    TempDirCommit(const TempDirCommit&) = delete;
    TempDirCommit& operator=(const TempDirCommit&) = delete;

    // The temporary directory to write into (`<finalPath>.tmp.<pid>`).
    const std::string& path() const { return tempPath_; }
    const std::string& finalPath() const { return finalPath_; }
    bool committed() const { return committed_; }

    // Moves the temporary directory to finalPath(); may be called once.
    void commit();

  private:
    std::string finalPath_, tempPath_;
    bool committed_ = false;
};

}  // namespace weft
