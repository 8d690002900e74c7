// A real recording whose depth has an empty row and column every 4-5 pixels (depth registered to the
// colour camera: ../shared/data/kinfu_sample_50). With hole-tolerant frame normals and a model whose
// unobserved voxels are unknown rather than free space, the default pipeline tracks every frame and
// beats InfiniTAM's CPU build on it (ATE 3.4 mm against the recording's poses); before, 49 of the 50
// frames failed. Bridging one-pixel gaps in the depth conversion lowers the error further.

#include <gtest/gtest.h>

#include <filesystem>

#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/eval/TrajectoryError.h"
#include "voxfuse/io/ImageSource.h"

namespace voxfuse {
namespace {

struct KinfuRun {
    TrajectoryError error;
    int failed = 0;
};

// The whole sample through the default pipeline, with `settings`; skips the test without the data.
KinfuRun runKinfuSample(const MainEngineSettings& settings) {
    const std::string dir = std::string(VOXFUSE_SHARED_DATA_DIR) + "/kinfu_sample_50";
    auto source = openImageSource(dir);
    auto engine = MainEngine::create(settings, source->calib());
    RGBDFrame frame;
    std::vector<TimedPose> trajectory;
    KinfuRun run;
    while (source->next(frame)) {
        const FrameResult r = engine->processFrame(frame, nullptr);
        run.failed += r.quality == TrackingQuality::Failed;
        trajectory.push_back({frame.timestamp_s, r.T_world_camera});
    }
    run.error = evaluateTrajectory(trajectory, source->groundTruth());
    std::printf("[ kinfu    ] gap tolerance %.2f: ATE RMSE %.2f mm (max %.2f, %d pairs), %d failed\n",
                settings.depth_gap_tolerance, 1000 * run.error.ate_rmse_m, 1000 * run.error.ate_max_m, run.error.pairs,
                run.failed);
    return run;
}

bool haveKinfuSample() {
    return std::filesystem::exists(std::string(VOXFUSE_SHARED_DATA_DIR) + "/kinfu_sample_50/intrinsics.K.txt");
}

TEST(RealSensorTrackingTest, DepthWithHoleLinesIsTrackedOnEveryFrame) {
    if (!haveKinfuSample())
        GTEST_SKIP() << "../shared/data/kinfu_sample_50 not found under " << VOXFUSE_SHARED_DATA_DIR;
    const KinfuRun run = runKinfuSample(MainEngineSettings());
    EXPECT_EQ(run.failed, 0);
    EXPECT_EQ(run.error.pairs, 50);
    EXPECT_LT(run.error.ate_rmse_m, 0.0030) << "2.76 mm with one-pixel gaps bridged (InfiniTAM's CPU build: 3.4 mm)";
}

// Without bridging, the hole lines leave unobserved voxel lines in the map and the error rises
// (3.01 mm); the bridged run must keep its lead.
TEST(RealSensorTrackingTest, BridgingOnePixelDepthGapsLowersTheError) {
    if (!haveKinfuSample())
        GTEST_SKIP() << "../shared/data/kinfu_sample_50 not found under " << VOXFUSE_SHARED_DATA_DIR;
    MainEngineSettings kept;
    kept.depth_gap_tolerance = 0.f;
    const KinfuRun with_gaps = runKinfuSample(kept);
    const KinfuRun bridged = runKinfuSample(MainEngineSettings());
    EXPECT_EQ(with_gaps.failed, 0);
    EXPECT_LT(bridged.error.ate_rmse_m, with_gaps.error.ate_rmse_m - 0.0001);
}

}  // namespace
}  // namespace voxfuse
