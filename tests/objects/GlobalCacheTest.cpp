// The global cache: blocks come back as they went in, from memory or from a swap file; slots are
// reused; on disk no block is held in memory; a swap file that cannot be made, or whose path exists,
// is an error naming it.

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "voxfuse/core/Error.h"
#include "voxfuse/objects/GlobalCache.h"

namespace voxfuse {
namespace {

void roundTrip(GlobalCache& cache) {
    const std::size_t bytes = cache.blockBytes();
    std::vector<unsigned char> blocks(bytes * 300);
    for (std::size_t i = 0; i < blocks.size(); ++i) blocks[i] = (unsigned char)(i * 7 + i / bytes);
    std::vector<int> slots(300);
    cache.store(blocks.data(), 300, slots.data());
    EXPECT_EQ(cache.storedBlocks(), 300);
    std::vector<unsigned char> back(bytes * 3);
    const int some[3] = {slots[299], slots[0], slots[150]};
    cache.take(some, 3, back.data());
    EXPECT_EQ(0, std::memcmp(back.data(), blocks.data() + 299 * bytes, bytes));
    EXPECT_EQ(0, std::memcmp(back.data() + bytes, blocks.data(), bytes));
    EXPECT_EQ(0, std::memcmp(back.data() + 2 * bytes, blocks.data() + 150 * bytes, bytes));
    EXPECT_EQ(cache.storedBlocks(), 297);
    // Freed slots are reused before the cache grows.
    int again[3];
    cache.store(blocks.data(), 3, again);
    for (int s : again) EXPECT_TRUE(s == some[0] || s == some[1] || s == some[2]);
    std::vector<unsigned char> one(bytes);
    cache.read(slots[42], one.data());
    EXPECT_EQ(0, std::memcmp(one.data(), blocks.data() + 42 * bytes, bytes));
}

TEST(GlobalCacheTest, BlocksComeBackFromMemory) {
    GlobalCache cache(512 * 4);
    EXPECT_FALSE(cache.onDisk());
    roundTrip(cache);
    EXPECT_GE(cache.memoryBytes(), 300u * 512 * 4);
    EXPECT_EQ(cache.fileBytes(), 0u);
}

TEST(GlobalCacheTest, BlocksComeBackFromASwapFileAndStayOutOfMemory) {
    const std::string path = (std::filesystem::temp_directory_path() / "voxfuse_cache_test.bin").string();
    GlobalCache cache(512 * 10, path);
    EXPECT_TRUE(cache.onDisk());
    EXPECT_FALSE(std::filesystem::exists(path)) << "the swap file is unlinked as soon as it is open";
    roundTrip(cache);
    EXPECT_EQ(cache.memoryBytes(), 0u);
    EXPECT_EQ(cache.fileBytes(), 300u * 512 * 10);
}

TEST(GlobalCacheTest, ASwapFileThatCannotBeMadeIsNamed) {
    const std::string path = "/nonexistent_folder_voxfuse/swap.bin";
    try {
        GlobalCache cache(512, path);
        ADD_FAILURE() << "made a swap file in a missing folder";
    } catch (const IoError& e) {
        EXPECT_EQ(e.file(), path);
        EXPECT_NE(std::string(e.what()).find("cannot create the swap file"), std::string::npos);
    }
    EXPECT_THROW(GlobalCache(0), ConfigError);
    GlobalCache cache(64);
    char block[64];
    EXPECT_THROW(cache.read(0, block), Error) << "a slot never stored";
}

TEST(GlobalCacheTest, AnExistingFileIsNeverTakenForTheSwapFile) {
    // The swap file is unlinked as soon as it is open: a path that names a user's file or a map would
    // lose it.
    const std::string path =
        (std::filesystem::temp_directory_path() / ("voxfuse_cache_precious_" + std::to_string(::getpid()))).string();
    { std::ofstream(path) << "keep me\n"; }
    try {
        GlobalCache cache(512, path);
        ADD_FAILURE() << "an existing file became the swap file";
    } catch (const IoError& e) {
        EXPECT_EQ(e.file(), path);
        EXPECT_NE(std::string(e.what()).find("must be a new path"), std::string::npos) << e.what();
    }
    std::ifstream in(path);
    std::string line;
    EXPECT_TRUE(std::getline(in, line) && line == "keep me") << "the file was touched";
    std::filesystem::remove(path);
}

}  // namespace
}  // namespace voxfuse
