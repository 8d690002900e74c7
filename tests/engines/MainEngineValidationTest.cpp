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
    for (auto [min_m, max_m] : {std::pair{nan, 3.f}, {0.2f, nan}, {3.f, 2.f}, {2.f, 2.f}, {-1.f, 2.f}, {0.2f, INFINITY}}) {
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
