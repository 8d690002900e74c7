// Output files appear whole or not at all, and a failed write says why.

#include <gtest/gtest.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <functional>
#include <string>

#include "IoTestUtil.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/AtomicFile.h"

namespace voxfuse {
namespace {

namespace fs = std::filesystem;
using test::readBytes;
using test::ScratchDir;
using test::writeBytes;

// The names in a folder other than `except`.
std::vector<std::string> namesIn(const std::string& folder) {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(folder)) names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

std::string errorOf(const std::function<void()>& f) {
    try {
        f();
    } catch (const IoError& e) {
        return e.what();
    }
    return "";
}

TEST(AtomicFile, TheTargetChangesOnlyWhenTheNewFileIsComplete) {
    ScratchDir dir;
    const std::string path = dir.file("trajectory.txt");
    writeBytes(path, "earlier run\n");
    {
        AtomicFile file(path);
        file.stream() << "this run, half written";
        file.stream().flush();
        EXPECT_EQ(readBytes(path), "earlier run\n");  // a reader meanwhile sees the old file, whole
        ASSERT_EQ(namesIn(dir.path()).size(), 2u);
        EXPECT_TRUE(isPartialFileName(namesIn(dir.path())[0])) << namesIn(dir.path())[0];
        file.stream() << "\n";
        file.commit();
    }
    EXPECT_EQ(readBytes(path), "this run, half written\n");
    EXPECT_EQ(namesIn(dir.path()), std::vector<std::string>{"trajectory.txt"});
}

TEST(AtomicFile, AnAbandonedWriteLeavesTheTargetAndNoTemporaryFile) {
    ScratchDir dir;
    const std::string path = dir.file("summary.json");
    writeBytes(path, "{}\n");
    {
        AtomicFile file(path);
        file.stream() << "{\"frames\": ";
    }  // not committed: the run failed half way
    EXPECT_EQ(readBytes(path), "{}\n");
    EXPECT_EQ(namesIn(dir.path()), std::vector<std::string>{"summary.json"});

    EXPECT_THROW(writeFileAtomically(path,
                                     [](const std::string& temporary) {
                                         writeBytes(temporary, "partial");
                                         throw IoError(temporary, "the encoder failed");
                                     }),
                 IoError);
    EXPECT_EQ(readBytes(path), "{}\n");
    EXPECT_EQ(namesIn(dir.path()), std::vector<std::string>{"summary.json"});
}

TEST(AtomicFile, FileNameWritersGetATemporaryNameWithTheSameExtension) {
    ScratchDir dir;
    const std::string path = dir.file("render_000001.png");
    std::string seen;
    writeFileAtomically(path, [&](const std::string& temporary) {
        seen = temporary;
        writeBytes(temporary, "png");
    });
    EXPECT_EQ(fs::path(seen).extension(), ".png");
    EXPECT_EQ(fs::path(seen).parent_path(), fs::path(path).parent_path());
    EXPECT_EQ(readBytes(path), "png");
    // A writer that leaves no file is an error naming the target, not a silent success.
    const std::string reason =
        errorOf([&] { writeFileAtomically(dir.file("nothing.png"), [](const std::string&) {}); });
    EXPECT_NE(reason.find("nothing.png"), std::string::npos) << reason;
    EXPECT_FALSE(fs::exists(dir.file("nothing.png")));
}

TEST(AtomicFile, FailuresNameTheTargetAndTheCause) {
    ScratchDir dir;
    const std::string folder_error = errorOf([&] { AtomicFile file(dir.path()); });
    EXPECT_NE(folder_error.find(dir.path()), std::string::npos) << folder_error;
    EXPECT_NE(folder_error.find("is a folder, not a file"), std::string::npos) << folder_error;

    const std::string missing = dir.path() + "/no_such_folder/mesh.ply";
    const std::string missing_error = errorOf([&] { AtomicFile file(missing); });
    EXPECT_NE(missing_error.find(missing), std::string::npos) << missing_error;
    EXPECT_NE(missing_error.find("no such folder"), std::string::npos) << missing_error;

    writeBytes(dir.file("a_file"), "x");
    const std::string under_file = errorOf([&] { requireWritable(dir.file("a_file") + "/summary.json"); });
    EXPECT_NE(under_file.find("is not a folder"), std::string::npos) << under_file;
    EXPECT_EQ(namesIn(dir.path()), std::vector<std::string>{"a_file"});  // the probe left nothing
}

TEST(AtomicFile, WriteFailuresAreNamedInWords) {
    EXPECT_NE(writeFailureReason("/tmp/x", ENOSPC).find("disk full"), std::string::npos);
    EXPECT_NE(writeFailureReason("/tmp/x", EDQUOT).find("quota"), std::string::npos);
    EXPECT_NE(writeFailureReason("/tmp/x", EROFS).find("read-only"), std::string::npos);
    EXPECT_NE(writeFailureReason("/tmp/x", EACCES).find("permission denied"), std::string::npos);
    EXPECT_NE(writeFailureReason("/tmp/x", EFBIG).find("too large"), std::string::npos);
}

TEST(AtomicFile, PartialNamesAreRecognised) {
    EXPECT_TRUE(isPartialFileName(".mesh.partial-1234.ply"));
    EXPECT_TRUE(isPartialFileName(".trajectory.partial-7.txt"));
    EXPECT_FALSE(isPartialFileName("mesh.ply"));
    EXPECT_FALSE(isPartialFileName("mesh.partial-1.ply"));  // not hidden: a user's file
    EXPECT_FALSE(isPartialFileName(""));
}

}  // namespace
}  // namespace voxfuse
