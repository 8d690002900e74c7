// Tracking through the whole pipeline on the bundled synthetic sequence (exact ground truth).

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/eval/TrajectoryError.h"
#include "voxfuse/io/ImageSource.h"

namespace voxfuse {
namespace {

struct TrackedRun {
    std::vector<TimedPose> trajectory;
    std::vector<FrameResult> results;
    AllocationStats allocation;
    TrajectoryError error;
};

// Runs the default engine (hash, default tracker) over the first `frames` frames; `noise_frame` >= 0
// has its depth replaced by uniform noise.
TrackedRun runBundledSequence(int frames, int noise_frame) {
    auto source = openImageSource(std::string(VOXFUSE_SOURCE_DIR) + "/data/synthetic_room");
    MainEngineSettings s;
    s.voxel_type = VoxelType::S;
    s.remove_empty_blocks_every = 0;  // removal runs every N fused frames: keep it out of the comparison
    auto engine = MainEngine::create(s, source->calib());
    TrackedRun run;
    RGBDFrame frame;
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> noise(2000, 20000);  // 0.4 m .. 4 m at the TUM scale
    while (int(run.results.size()) < frames && source->next(frame)) {
        if (frame.index == noise_frame)
            for (std::size_t i = 0; i < frame.depth_raw.pixelCount(); ++i)
                frame.depth_raw.host()[i] = std::uint16_t(noise(rng));
        run.results.push_back(engine->processFrame(frame, nullptr));
        run.trajectory.push_back({frame.timestamp_s, run.results.back().T_world_camera});
    }
    run.allocation = engine->allocationStats();
    run.error = evaluateTrajectory(run.trajectory, source->groundTruth());
    return run;
}

TEST(MainEngineTrackingTest, BundledSequenceIsTrackedWithinFiveMillimetres) {
    const TrackedRun run = runBundledSequence(100, -1);
    std::printf("[ tracking ] bundled sequence: ATE RMSE %.2f mm, max %.2f mm over %d poses; RPE %.2f mm/s\n",
                1000 * run.error.ate_rmse_m, 1000 * run.error.ate_max_m, run.error.pairs,
                1000 * run.error.rpe_trans_m_per_s);
    EXPECT_EQ(run.error.pairs, 100);
    EXPECT_LT(run.error.ate_rmse_m, 0.005);
    for (const FrameResult& r : run.results) EXPECT_NE(r.quality, TrackingQuality::Failed);
}

TEST(MainEngineTrackingTest, NoiseFrameFailsAndDoesNotCorruptTheMap) {
    const int kNoiseFrame = 15;
    const TrackedRun clean = runBundledSequence(30, -1);
    const TrackedRun noisy = runBundledSequence(30, kNoiseFrame);
    ASSERT_EQ(noisy.results.size(), 30u);
    const FrameResult& bad = noisy.results[kNoiseFrame];
    EXPECT_EQ(bad.quality, TrackingQuality::Failed);
    EXPECT_FALSE(bad.fused);
    // The pose is held at the last good one, and tracking resumes on the next frame.
    for (int i = 0; i < 16; ++i) EXPECT_EQ(bad.T_world_camera.m[i], noisy.results[kNoiseFrame - 1].T_world_camera.m[i]);
    for (int k = kNoiseFrame + 1; k < 30; ++k)
        EXPECT_NE(noisy.results[k].quality, TrackingQuality::Failed) << "frame " << k;
    // Fusing noise would allocate blocks all over the frustum; skipping it leaves the map as without it.
    EXPECT_NEAR(noisy.allocation.blocks_allocated, clean.allocation.blocks_allocated,
                0.01 * clean.allocation.blocks_allocated);
    EXPECT_LT(noisy.error.ate_rmse_m, 0.005);
}

// A camera's first frames often hold no depth yet: they fail, but are not "lost" (there is no map to be
// lost in), and the first frame with depth starts the map, as the first frame would have.
TEST(MainEngineTrackingTest, FramesWithoutDepthBeforeTheMapStartsAreNotLost) {
    auto source = openImageSource(std::string(VOXFUSE_SOURCE_DIR) + "/data/synthetic_room");
    auto engine = MainEngine::create(MainEngineSettings(), source->calib());
    RGBDFrame frame;
    std::vector<FrameResult> results;
    while (results.size() < 6 && source->next(frame)) {
        if (frame.index < 2) frame.depth_raw.memory().fill(0);
        results.push_back(engine->processFrame(frame, nullptr));
    }
    ASSERT_EQ(results.size(), 6u);
    for (int k = 0; k < 2; ++k) {
        EXPECT_FALSE(results[k].fused) << "frame " << k;
        EXPECT_NE(results[k].status, TrackingStatus::Lost) << "frame " << k;
    }
    for (int k = 2; k < 6; ++k) {
        EXPECT_TRUE(results[k].fused) << "frame " << k;
        EXPECT_EQ(results[k].status, TrackingStatus::Tracking) << "frame " << k;
    }
}

}  // namespace
}  // namespace voxfuse
