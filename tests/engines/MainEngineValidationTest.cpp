// MainEngine::create refuses settings it cannot honour with a message naming them, before any memory
// is taken; and a frame without usable depth is never reported as well tracked.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "voxfuse/core/Error.h"
#include "voxfuse/engines/MainEngine.h"

namespace voxfuse {
namespace {

RGBDCalib smallCalib() {
    RGBDCalib calib;
    calib.depth = calib.rgb = Intrinsics{64, 48, 50.f, 50.f, 31.5f, 23.5f};
    calib.disparity = DisparityCalib::affine(0.001f);
    return calib;
}

// The ConfigError's message for these settings ("" if none was thrown).
std::string createError(const MainEngineSettings& s) {
    try {
        MainEngine::create(s, smallCalib());
    } catch (const ConfigError& e) {
        return e.what();
    }
    return "";
}

void expectRefused(const MainEngineSettings& s, const std::string& part) {
    const std::string message = createError(s);
    EXPECT_NE(message.find(part), std::string::npos) << "message: '" << message << "'";
}

TEST(MainEngineCreate, TheDepthRangeMustBeARange) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (auto [min_m, max_m] :
         {std::pair{nan, 3.f}, {0.2f, nan}, {3.f, 2.f}, {2.f, 2.f}, {-1.f, 2.f}, {0.2f, INFINITY}}) {
        SCOPED_TRACE(std::to_string(min_m) + " .. " + std::to_string(max_m));
        MainEngineSettings s;
        s.scene.view_frustum_min_m = min_m;
        s.scene.view_frustum_max_m = max_m;
        expectRefused(s, "--min-depth, --max-depth");
    }
}

TEST(MainEngineCreate, TheDepthGapToleranceIsAFractionUpToAHalf) {
    for (float tolerance : {-0.01f, 0.51f, std::numeric_limits<float>::quiet_NaN()}) {
        SCOPED_TRACE(tolerance);
        MainEngineSettings s;
        s.depth_gap_tolerance = tolerance;
        expectRefused(s, "--depth-gap-tolerance");
    }
    for (float tolerance : {0.f, 0.5f}) {
        MainEngineSettings s;
        s.depth_gap_tolerance = tolerance;
        EXPECT_EQ(createError(s), "") << tolerance;
    }
}

TEST(MainEngineCreate, VoxelSizeAndMuMustBeFinite) {
    MainEngineSettings s;
    s.scene.voxel_size_m = INFINITY;
    expectRefused(s, "need voxel size > 0 and mu > voxel size");
    s.scene.voxel_size_m = 0.005f;
    s.scene.mu_m = INFINITY;
    expectRefused(s, "both finite");
}

TEST(MainEngineCreate, ADenseVolumeFarFromTheOriginIsRefusedNotOverflowed) {
    MainEngineSettings s;
    s.index_type = IndexType::Dense;
    s.dense_offset = {2147483600, 0, 0};  // offset + size would overflow an int
    s.dense_size = {16, 16, 16};
    expectRefused(s, "on axis x it spans 2147483600 .. 2147483616");
    s.dense_offset = {0, -(1 << 24) - 1, 0};
    expectRefused(s, "--volume-offset, --volume-size");
    s.dense_offset = {0, 0, 0};
    s.dense_size = {16, 0, 16};
    expectRefused(s, "dense volume size must be positive");
}

TEST(MainEngineCreate, ADenseVolumeLargerThanMemorySaysHowMuchItNeeds) {
    MainEngineSettings s;
    s.index_type = IndexType::Dense;
    s.voxel_type = VoxelType::SRgb;
    s.dense_offset = {-32768, -32768, 0};
    s.dense_size = {65536, 65536, 4096};  // 2^44 voxels
    const std::string message = createError(s);
    EXPECT_NE(message.find("65536x65536x4096 's_rgb' voxels needs"), std::string::npos) << message;
    EXPECT_NE(message.find("GiB"), std::string::npos) << message;
    EXPECT_NE(message.find("--volume-size"), std::string::npos) << message;
    EXPECT_NE(message.find("--index hash"), std::string::npos) << message;
}

TEST(MainEngineCreate, AHashTableLargerThanMemorySaysWhatToChange) {
    MainEngineSettings s;
    s.hash.bucket_count = 1 << 30;
    s.hash.excess_entry_count = (1 << 30) - 1;
    const std::string message = createError(s);
    EXPECT_NE(message.find("hash table of"), std::string::npos) << message;
    EXPECT_NE(message.find("--hash-buckets"), std::string::npos) << message;
}

// The automatic block ceiling: the table's entries and the free memory of the map's device (on the GPU
// with room for the two copies a growth holds), DESIGN.md's 2^18 where the free memory is unknown.
TEST(AutomaticBlockCeiling, FollowsTheTableAndTheFreeMemoryOfItsDevice) {
    constexpr double kGiB = double(1ull << 30);
    const VoxelBlockHashSettings design;  // 2^20 buckets + 2^17 excess entries
    const int entries = design.bucket_count * design.entries_per_bucket + design.excess_entry_count;
    const std::size_t srgb = sizeof(VoxelSRgb);
    EXPECT_EQ(automaticMaxBlockCount(Device::CPU, srgb, design, 64 * kGiB), entries);  // every entry can have its block
    EXPECT_EQ(automaticMaxBlockCount(Device::CUDA, srgb, design, 64 * kGiB), entries);
    EXPECT_EQ(automaticMaxBlockCount(Device::CPU, srgb, design, 0.0), 1 << 18);   // free memory unknown
    EXPECT_EQ(automaticMaxBlockCount(Device::CUDA, srgb, design, 0.0), 1 << 18);  // no GPU to ask

    VoxelBlockHashSettings small = design;
    small.bucket_count = 4096;
    small.excess_entry_count = 1024;
    EXPECT_EQ(automaticMaxBlockCount(Device::CPU, srgb, small, 64 * kGiB), 5120);

    VoxelBlockHashSettings huge = design;
    huge.bucket_count = 1 << 24;
    EXPECT_EQ(automaticMaxBlockCount(Device::CPU, sizeof(VoxelS), huge, 1024 * kGiB),
              1 << 22);  // voxel offsets stay ints

    // 2 GiB free: the blocks and the tables fill three quarters of it, not more.
    const double free_bytes = 2 * kGiB;
    const int n = automaticMaxBlockCount(Device::CPU, srgb, design, free_bytes);
    VoxelBlockHashSettings with_n = design;
    with_n.max_block_count = n;
    const double used = double(VoxelBlockHash::tableBytesFor(with_n)) + double(n) * double(srgb * kBlockVoxelCount);
    EXPECT_LE(used, 0.75 * free_bytes);
    EXPECT_GT(used + double(1 << 16) * double(srgb * kBlockVoxelCount + 2 * sizeof(int)), 0.75 * free_bytes);
    EXPECT_EQ(n % (1 << 16), 0) << "in steps of 2^16 blocks: the same on one machine from run to run";
    EXPECT_LT(n, entries);
    // On the GPU a growth holds the old array and the new one: both fit in three quarters of the free
    // memory beside the tables, and each block counts twice.
    const int on_gpu = automaticMaxBlockCount(Device::CUDA, srgb, design, free_bytes);
    with_n.max_block_count = on_gpu;
    const double gpu_used =
        double(VoxelBlockHash::tableBytesFor(with_n)) + 2.0 * double(on_gpu) * double(srgb * kBlockVoxelCount);
    EXPECT_LE(gpu_used, 0.75 * free_bytes);
    EXPECT_EQ(on_gpu % (1 << 16), 0);
    EXPECT_GE(on_gpu, n / 2 - (1 << 16));
    EXPECT_LE(on_gpu, n / 2 + (1 << 16));
    // Larger voxels, fewer blocks; no memory beside the tables, still one block.
    EXPECT_LT(automaticMaxBlockCount(Device::CPU, sizeof(VoxelFRgb), design, free_bytes), n);
    EXPECT_EQ(automaticMaxBlockCount(Device::CPU, srgb, design, 1024.0), 1);
}

TEST(MainEngineCreate, TheEngineSettingsHoldTheCeilingItChose) {
    MainEngineSettings s;
    ASSERT_EQ(s.hash.max_block_count, kAutomaticBlockCount);
    s.hash.bucket_count = 4096;
    s.hash.excess_entry_count = 1024;
    s.hash.max_bucket_count = 16384;  // as many blocks as the table has entries once it has grown
    EXPECT_EQ(MainEngine::create(s, smallCalib())->settings().hash.max_block_count, 16384 + 4096);
    s.hash.max_bucket_count = 0;  // a fixed table
    EXPECT_EQ(MainEngine::create(s, smallCalib())->settings().hash.max_block_count, 5120);
    s.device = Device::CPU;
    s.hash.max_block_count = 77;  // asked for: kept
    EXPECT_EQ(MainEngine::create(s, smallCalib())->settings().hash.max_block_count, 77);
    s.index_type = IndexType::Dense;
    s.hash.max_block_count = kAutomaticBlockCount;  // the dense index has no hash to size
    s.dense_size = {16, 16, 16};
    EXPECT_EQ(MainEngine::create(s, smallCalib())->settings().hash.max_block_count, kAutomaticBlockCount);
}

// All-zero depth: nothing to track or fuse. The tracker must not call such a frame good, neither the
// first frame (no map yet) nor a later one.
TEST(EmptyDepthFrame, IsNeverReportedAsWellTracked) {
    MainEngineSettings s;
    s.voxel_type = VoxelType::S;
    s.scene.voxel_size_m = 0.02f;
    s.scene.mu_m = 0.08f;
    auto engine = MainEngine::create(s, smallCalib());
    RGBDFrame empty;
    empty.depth_raw = Image<std::uint16_t>(Vec2i{64, 48});
    std::fill_n(empty.depth_raw.host(), empty.depth_raw.pixelCount(), std::uint16_t(0));
    for (int i = 0; i < 3; ++i) {
        SCOPED_TRACE(i);
        empty.index = i;
        const FrameResult r = engine->processFrame(empty, nullptr);
        EXPECT_EQ(r.quality, TrackingQuality::Failed) << "tracking quality " << toString(r.quality);
        EXPECT_FALSE(r.fused);
    }
}

}  // namespace
}  // namespace voxfuse
