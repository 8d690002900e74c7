#pragma once
// Shared helpers for the io tests: a scratch folder per test, small file writers, and where the
// repository and the shared recorded data are.

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "voxfuse/core/Image.h"

namespace voxfuse {
namespace test {

// A fresh folder under ::testing::TempDir(), removed when the test ends.
class ScratchDir {
public:
    ScratchDir() {
        static std::atomic<int> counter{0};
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        const std::string name = std::string("voxfuse_io_") + (info ? info->name() : "test") + "_" +
                                 std::to_string(::getpid()) + "_" + std::to_string(counter++);
        path_ = std::filesystem::path(::testing::TempDir()) / name;
        std::filesystem::remove_all(path_);
        std::filesystem::create_directories(path_);
    }
    ~ScratchDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;

    // Absolute path of `relative` inside the folder (its parent folders are created).
    std::string file(const std::string& relative) const {
        const auto p = path_ / relative;
        std::filesystem::create_directories(p.parent_path());
        return p.string();
    }
    std::string path() const { return path_.string(); }

private:
    std::filesystem::path path_;
};

inline void writeBytes(const std::string& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    ASSERT_TRUE(out.good()) << path;
}

inline std::string readBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Deterministic test images: every pixel different, values depending on `seed`.
inline Image<std::uint16_t> makeDepth(Vec2i size, int seed) {
    Image<std::uint16_t> image(size);
    for (int y = 0; y < size.y; ++y)
        for (int x = 0; x < size.x; ++x) image.at(x, y) = std::uint16_t(seed * 1000 + y * 97 + x * 13 + 1);
    return image;
}
inline Image<Vec4u8> makeRgb(Vec2i size, int seed) {
    Image<Vec4u8> image(size);
    for (int y = 0; y < size.y; ++y)
        for (int x = 0; x < size.x; ++x)
            image.at(x, y) =
                Vec4u8{std::uint8_t(seed * 40 + x), std::uint8_t(seed * 7 + y * 3), std::uint8_t(200 - x - y), 255};
    return image;
}

template <typename T>
bool samePixels(const Image<T>& a, const Image<T>& b) {
    if (a.size() != b.size()) return false;
    return std::memcmp(a.host(), b.host(), a.pixelCount() * sizeof(T)) == 0;
}

// The repository root: the build's VOXFUSE_SOURCE_DIR (__FILE__ may be relative: ccache with
// CCACHE_BASEDIR makes it so), else found from this file's location (tests/io/IoTestUtil.h).
inline std::filesystem::path repositoryDir() {
#ifdef VOXFUSE_SOURCE_DIR
    return std::filesystem::path(VOXFUSE_SOURCE_DIR);
#else
    return std::filesystem::absolute(std::filesystem::path(__FILE__)).parent_path().parent_path().parent_path();
#endif
}

// ../shared/data beside the checkout, as a compile definition; empty when not defined.
inline std::string sharedDataDir() {
#ifdef VOXFUSE_SHARED_DATA_DIR
    return VOXFUSE_SHARED_DATA_DIR;
#else
    return "";
#endif
}

}  // namespace test
}  // namespace voxfuse

// Skips the test when a data set from ../shared/data is not there.
#define VOXFUSE_REQUIRE_SHARED_DATA(subfolder, out_path)                                      \
    const std::string out_path = ::voxfuse::test::sharedDataDir() + "/" + (subfolder);        \
    if (::voxfuse::test::sharedDataDir().empty() || !std::filesystem::is_directory(out_path)) \
    GTEST_SKIP() << "../shared/data not found: " << out_path << " (define VOXFUSE_SHARED_DATA_DIR)"
