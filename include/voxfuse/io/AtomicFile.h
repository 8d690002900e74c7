#pragma once
// Output files that no reader ever sees half-written. The bytes go to a hidden temporary file beside
// the target (same folder: the rename never crosses file systems), which replaces the target only
// once everything was written, flushed and closed without error. A failed or abandoned write leaves
// the target as it was and removes the temporary file. Every failure is an IoError naming the target
// and the cause in words: "disk full", "no such folder", "is a folder, not a file", "permission
// denied", "read-only file system".

#include <fstream>
#include <functional>
#include <string>

namespace voxfuse {

class AtomicFile {
public:
    // Opens the temporary file (binary). IoError when the target cannot be written at all.
    explicit AtomicFile(const std::string& path);
    // Removes the temporary file unless commit() succeeded.
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    std::ostream& stream() { return out_; }
    // Throws the IoError a write failure deserves when the stream has failed (writers that stream a
    // lot call it now and then, so that a full disk stops them early).
    void check();
    // Flushes and closes the temporary file and renames it over the target.
    void commit();

    const std::string& path() const { return path_; }

private:
    std::string path_;
    std::string temporary_;
    std::ofstream out_;
    bool committed_ = false;
};

// For writers that insist on a file name of their own (OctoMap): `write` writes to the
// temporary path it is given (beside `path`, with the same extension, so that format-by-extension
// writers still work); the file is renamed into place when `write` returns. If `write` throws or
// leaves no file, or the disk is full after it (the writer may not have checked its last flush), the
// target is untouched and the IoError says why.
void writeFileAtomically(const std::string& path, const std::function<void(const std::string& temporary_path)>& write);

// Throws the IoError that writing `path` would end with (a folder where the file should be, a
// missing folder, no permission, a full disk), by creating and removing its temporary file: for
// checks before a long run whose outputs go there.
void requireWritable(const std::string& path);

// Why writing `path` failed, in words, from the errno of the failed call (ENOSPC: "disk full", ...).
// Also says "disk full" when the folder's file system has no space left whatever the errno was
// (streams do not always keep it).
std::string writeFailureReason(const std::string& path, int error_number);

// True for the hidden temporary names AtomicFile uses (".NAME.partial-PID.EXT"): what an
// interrupted process may leave behind.
bool isPartialFileName(const std::string& file_name);

}  // namespace voxfuse
