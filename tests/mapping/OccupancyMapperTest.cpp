// OccupancyMapper: free space along beams, occupied endpoints, subsampling, the non-blocking queue, .bt output.

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "SyntheticViews.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/mapping/OccupancyMapper.h"

namespace voxfuse {
namespace {

#ifndef VOXFUSE_WITH_OCTOMAP
TEST(OccupancyMapperTest, ConstructorSaysOctomapIsMissing) {
    EXPECT_THROW(OccupancyMapper(OccupancySettings{}), ConfigError);
    GTEST_SKIP() << "built without OctoMap (liboctomap-dev): the other occupancy tests are skipped";
}
#else

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

Image<float> constantDepth(const Intrinsics& intrinsics, float depth_m) {
    Image<float> depth(intrinsics.size());
    for (std::size_t i = 0; i < depth.pixelCount(); ++i) depth.host()[i] = depth_m;
    return depth;
}

// Off the 5 cm cell boundaries so that no query point sits on a face between two cells.
const Eigen::Vector3f kEye(1.01f, 0.02f, 0.51f);
Mat4f lookingAlongX() { return test::lookAt(kEye, kEye + Eigen::Vector3f::UnitX()); }
Vec3f onCentralRay(float distance_m) { return Vec3f{kEye.x() + distance_m, kEye.y(), kEye.z()}; }

// A wall 2 m in front of the camera, facing it: free up to the wall, occupied at it, unknown behind.
TEST(OccupancyMapperTest, WallIsOccupiedWithFreeSpaceBeforeAndUnknownBehind) {
    OccupancySettings settings;
    settings.resolution_m = 0.05f;
    settings.pixel_step = 1;
    const Intrinsics intrinsics = test::kinectIntrinsics(160, 120);
    OccupancyMapper mapper(settings);
    ASSERT_TRUE(mapper.submit(constantDepth(intrinsics, 2.0f), intrinsics, lookingAlongX()));
    mapper.finish();

    for (float d = 0.1f; d < 1.94f; d += 0.05f)
        EXPECT_EQ(mapper.occupancyAt(onCentralRay(d)), Occupancy::Free) << "at " << d << " m";
    EXPECT_EQ(mapper.occupancyAt(onCentralRay(2.0f)), Occupancy::Occupied);
    for (float d = 2.06f; d < 3.0f; d += 0.05f)
        EXPECT_EQ(mapper.occupancyAt(onCentralRay(d)), Occupancy::Unknown) << "at " << d << " m";
    EXPECT_EQ(mapper.occupancyAt(onCentralRay(-0.5f)), Occupancy::Unknown) << "behind the camera";
}

// Beams longer than max_range clear space up to it and mark nothing occupied.
TEST(OccupancyMapperTest, BeamsBeyondMaxRangeOnlyClearSpace) {
    OccupancySettings settings;
    settings.pixel_step = 2;
    settings.max_range_m = 1.0f;
    const Intrinsics intrinsics = test::kinectIntrinsics(160, 120);
    OccupancyMapper mapper(settings);
    mapper.submit(constantDepth(intrinsics, 2.0f), intrinsics, lookingAlongX());
    mapper.finish();
    EXPECT_EQ(mapper.occupancyAt(onCentralRay(0.5f)), Occupancy::Free);
    EXPECT_EQ(mapper.occupancyAt(onCentralRay(2.0f)), Occupancy::Unknown);
}

TEST(OccupancyMapperTest, FrameAndPixelStepsSubsample) {
    OccupancySettings settings;
    settings.frame_step = 3;
    settings.pixel_step = 4;
    settings.queue_capacity = 16;  // room for every mapped frame: nothing may be dropped here
    const Intrinsics intrinsics = test::kinectIntrinsics(160, 120);
    Image<float> depth = constantDepth(intrinsics, 1.5f);
    depth.at(4, 8) = 0.f;  // a sampled pixel without a measurement is no beam
    depth.at(5, 8) = 0.f;  // an unsampled one changes nothing
    OccupancyMapper mapper(settings);
    for (int i = 0; i < 10; ++i) EXPECT_TRUE(mapper.submit(depth, intrinsics, lookingAlongX()));
    mapper.finish();

    const OccupancyStats s = mapper.stats();
    EXPECT_EQ(s.frames_submitted, 10);
    EXPECT_EQ(s.frames_skipped, 6);  // frames 0, 3, 6 and 9 are mapped
    EXPECT_EQ(s.frames_dropped, 0);
    EXPECT_EQ(s.frames_inserted, 4);
    EXPECT_EQ(s.points_inserted, 4 * (40 * 30 - 1));
    EXPECT_GT(s.insert_ms, 0.0);
}

// The fusion loop must never wait for the octree: with a one-frame queue a burst is mostly dropped.
TEST(OccupancyMapperTest, FullQueueDropsFramesWithoutBlocking) {
    OccupancySettings settings;
    settings.pixel_step = 1;  // full 640x480 frames: each insert takes far longer than a submit
    settings.queue_capacity = 1;
    const Intrinsics intrinsics = test::kinectIntrinsics(640, 480);
    const Image<float> depth = constantDepth(intrinsics, 2.0f);
    OccupancyMapper mapper(settings);
    const int burst = 20;
    int accepted = 0;
    const auto start = Clock::now();
    for (int i = 0; i < burst; ++i) accepted += mapper.submit(depth, intrinsics, lookingAlongX()) ? 1 : 0;
    const double burst_s = secondsSince(start);
    mapper.finish();

    const OccupancyStats s = mapper.stats();
    EXPECT_EQ(s.frames_submitted, burst);
    EXPECT_GT(s.frames_dropped, 0);
    EXPECT_EQ(s.frames_dropped, burst - accepted);
    EXPECT_EQ(s.frames_inserted, accepted);
    EXPECT_LT(burst_s * 1000.0, s.insert_ms)
        << "the burst took about as long as inserting: submit() waited for the worker";
}

TEST(OccupancyMapperTest, DestructionWithoutFinishDoesNotWaitForTheQueue) {
    OccupancySettings settings;
    settings.pixel_step = 1;
    settings.queue_capacity = 8;
    const Intrinsics intrinsics = test::kinectIntrinsics(640, 480);
    const Image<float> depth = constantDepth(intrinsics, 2.0f);

    OccupancyMapper timing(settings);
    timing.submit(depth, intrinsics, lookingAlongX());
    timing.finish();
    const double one_insert_s = timing.stats().insert_ms / 1000.0;

    auto mapper = std::make_unique<OccupancyMapper>(settings);
    for (int i = 0; i < 8; ++i) mapper->submit(depth, intrinsics, lookingAlongX());
    const auto start = Clock::now();
    mapper.reset();
    // At most the scan in hand is finished; the other seven are discarded, not inserted.
    const double destroy_s = secondsSince(start);
    EXPECT_LT(destroy_s, 4.0 * one_insert_s + 0.05) << "one insert takes " << one_insert_s << " s";
}

// The map can be read while the worker writes it (run under TSan to check the locking).
TEST(OccupancyMapperTest, QueriesWhileMappingSeeTheWallAppear) {
    OccupancySettings settings;
    settings.pixel_step = 2;
    const Intrinsics intrinsics = test::kinectIntrinsics(320, 240);
    const Image<float> depth = constantDepth(intrinsics, 2.0f);
    OccupancyMapper mapper(settings);
    for (int i = 0; i < 4; ++i) mapper.submit(depth, intrinsics, lookingAlongX());
    bool seen_occupied = false;
    for (const auto start = Clock::now(); !seen_occupied && secondsSince(start) < 30.0;) {
        seen_occupied = mapper.occupancyAt(onCentralRay(2.0f)) == Occupancy::Occupied;
        EXPECT_LE(mapper.stats().frames_inserted, 4);
    }
    EXPECT_TRUE(seen_occupied);
    mapper.finish();
    EXPECT_EQ(mapper.stats().frames_inserted + mapper.stats().frames_dropped, 4);
}

TEST(OccupancyMapperTest, WritesBinaryOctomapFile) {
    const Intrinsics intrinsics = test::kinectIntrinsics(160, 120);
    OccupancyMapper mapper(OccupancySettings{});
    mapper.submit(constantDepth(intrinsics, 2.0f), intrinsics, lookingAlongX());
    const std::filesystem::path path = std::filesystem::path(::testing::TempDir()) / "voxfuse_occupancy_test.bt";
    mapper.write(path.string());

    std::ifstream file(path, std::ios::binary);
    ASSERT_TRUE(file) << path;
    std::string line;
    std::getline(file, line);
    EXPECT_EQ(line.rfind("# Octomap OcTree binary file", 0), 0u) << line;
    bool has_id = false, has_resolution = false, has_data = false;
    long long nodes = 0;
    while (std::getline(file, line)) {
        has_id |= line == "id OcTree";
        has_resolution |= line.rfind("res 0.05", 0) == 0;
        if (line.rfind("size ", 0) == 0) nodes = std::stoll(line.substr(5));
        if (line == "data") {
            has_data = true;
            break;
        }
    }
    EXPECT_TRUE(has_id && has_resolution && has_data);
    EXPECT_GT(nodes, 0);
    const auto header_end = file.tellg();
    file.seekg(0, std::ios::end);
    EXPECT_GT(file.tellg() - header_end, 0) << "no tree after the header";
    std::filesystem::remove(path);
}

TEST(OccupancyMapperTest, UnwritablePathThrowsIoError) {
    OccupancyMapper mapper(OccupancySettings{});
    EXPECT_THROW(mapper.write("/nonexistent-dir/occupancy.bt"), IoError);
}

TEST(OccupancyMapperTest, RejectsBadSettingsAndMisuse) {
    OccupancySettings bad;
    bad.pixel_step = 0;
    EXPECT_THROW(OccupancyMapper{bad}, ConfigError);
    bad = OccupancySettings{};
    bad.resolution_m = 0.f;
    EXPECT_THROW(OccupancyMapper{bad}, ConfigError);

    OccupancyMapper mapper(OccupancySettings{});
    const Intrinsics intrinsics = test::kinectIntrinsics(160, 120);
    EXPECT_THROW(mapper.submit(Image<float>(Vec2i{80, 60}), intrinsics, Mat4f::identity()), ConfigError);
    mapper.finish();
    EXPECT_THROW(mapper.submit(constantDepth(intrinsics, 1.f), intrinsics, Mat4f::identity()), Error);
}

#endif

}  // namespace
}  // namespace voxfuse
