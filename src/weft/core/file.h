// weft/core/file.h — whole-file reads and crash-safe writes.
//
// Every output file weft writes goes through writeFileAtomic: the bytes land in
// a temporary sibling file which is then renamed over the target, so a reader
// (or a crash) sees either the old file or the complete new one, never a torn
// one. TempDirCommit does the same for a whole output directory. Every failure
// throws InputError naming the path and the system's reason (strerror).
#pragma once

#include <string>
#include <string_view>

namespace weft {

// Writes `bytes` to `path` atomically: writes and fsyncs a temporary file
// `<dir>/.<basename>.tmp.<pid>.<counter>` and renames it over `path`. On failure
// the temporary file is removed and InputError names `path` and the reason
// (missing or unwritable directory, disk full, `path` is a directory...).
void writeFileAtomic(const std::string& path, std::string_view bytes);

// The extension of `path` with its dot, in lower case ("a/B.EXR" -> ".exr"; "" if none),
// for picking a reader by file type.
std::string lowercaseExtension(const std::string& path);

// The whole file as bytes; InputError naming `path` if it is missing, a
// directory or unreadable.
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
