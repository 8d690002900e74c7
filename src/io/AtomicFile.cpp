// Output files written under a temporary name and renamed into place.

#include "voxfuse/io/AtomicFile.h"

#include <sys/statvfs.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "voxfuse/core/Error.h"

namespace voxfuse {

namespace fs = std::filesystem;

namespace {

constexpr const char* kPartialTag = ".partial-";

fs::path folderOf(const std::string& path) {
    const fs::path folder = fs::path(path).parent_path();
    return folder.empty() ? fs::path(".") : folder;
}

bool diskFull(const fs::path& folder) {
    struct statvfs s {};
    return ::statvfs(folder.c_str(), &s) == 0 && s.f_bavail == 0;
}

// The target must be a file name in an existing folder; says what is wrong otherwise.
void requireWritableTarget(const std::string& path) {
    std::error_code ec;
    if (path.empty()) throw IoError(path, "no file name given");
    if (fs::is_directory(path, ec)) throw IoError(path, "is a folder, not a file");
    const fs::path folder = folderOf(path);
    if (!fs::exists(folder, ec)) throw IoError(path, "no such folder: " + folder.string());
    if (!fs::is_directory(folder, ec)) throw IoError(path, folder.string() + " is not a folder");
}

// ".NAME.partial-PID.EXT" beside the target: hidden, never taken for an output, same extension.
std::string temporaryNameFor(const std::string& path) {
    const fs::path target(path);
    const std::string extension = target.extension().string();
    const std::string stem = extension.empty() ? target.filename().string() : target.stem().string();
    return (folderOf(path) / ("." + stem + kPartialTag + std::to_string(::getpid()) + extension)).string();
}

void moveIntoPlace(const std::string& temporary, const std::string& path) {
    if (std::rename(temporary.c_str(), path.c_str()) != 0) {
        const int error = errno;
        std::remove(temporary.c_str());
        throw IoError(path, "cannot move the finished file into place: " + writeFailureReason(path, error));
    }
}

}  // namespace

std::string writeFailureReason(const std::string& path, int error_number) {
    switch (error_number) {
        case ENOSPC:
            return "disk full (no space left on the device)";
        case EDQUOT:
            return "disk quota exceeded";
        case EROFS:
            return "read-only file system";
        case EACCES:
        case EPERM:
            return "permission denied";
        case ENOENT:
            return "no such folder";
        case EISDIR:
            return "is a folder, not a file";
        case ENOTDIR:
            return "a part of the path is not a folder";
        case EFBIG:
            return "file too large (for the file system, or the process's file size limit)";
        case ENAMETOOLONG:
            return "file name too long";
        case EIO:
            return "input/output error (a failing disk or a lost network share?)";
        default:
            break;
    }
    // Streams do not always keep errno: a folder without free space says it all the same.
    if (diskFull(folderOf(path))) return "disk full (no space left on the device)";
    return error_number != 0 ? std::string(std::strerror(error_number)) : std::string("write failed");
}

bool isPartialFileName(const std::string& file_name) {
    return !file_name.empty() && file_name[0] == '.' && file_name.find(kPartialTag) != std::string::npos;
}

AtomicFile::AtomicFile(const std::string& path) : path_(path) {
    requireWritableTarget(path_);
    temporary_ = temporaryNameFor(path_);
    errno = 0;
    out_.open(temporary_, std::ios::binary | std::ios::trunc);
    if (!out_) throw IoError(path_, "cannot create the file: " + writeFailureReason(path_, errno));
}

AtomicFile::~AtomicFile() {
    if (committed_) return;
    out_.close();
    std::remove(temporary_.c_str());
}

void AtomicFile::check() {
    if (!out_) throw IoError(path_, "cannot write: " + writeFailureReason(path_, errno));
}

void AtomicFile::commit() {
    errno = 0;
    out_.flush();
    check();
    out_.close();
    check();
    moveIntoPlace(temporary_, path_);
    committed_ = true;
}

void requireWritable(const std::string& path) {
    AtomicFile probe(path);  // removed again, uncommitted
    probe.stream() << "x";
    probe.stream().flush();
    probe.check();
}

void writeFileAtomically(const std::string& path, const std::function<void(const std::string&)>& write) {
    requireWritableTarget(path);
    const std::string temporary = temporaryNameFor(path);
    try {
        errno = 0;
        write(temporary);
    } catch (const IoError& e) {
        std::remove(temporary.c_str());
        throw IoError(path, e.reason());  // the reason, under the name the caller knows
    } catch (...) {
        std::remove(temporary.c_str());
        throw;
    }
    std::error_code ec;
    if (!fs::is_regular_file(temporary, ec)) throw IoError(path, "cannot write: " + writeFailureReason(path, errno));
    // Writers with files of their own may not check their last flush: a disk left full may have cut
    // the file short, and an incomplete file must not take the target's place.
    if (diskFull(folderOf(path))) {
        std::remove(temporary.c_str());
        throw IoError(path, "cannot write: disk full (no space left on the device; the file may be incomplete)");
    }
    moveIntoPlace(temporary, path);
}

}  // namespace voxfuse
