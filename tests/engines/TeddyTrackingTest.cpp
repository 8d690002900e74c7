// Real recorded frames: frame-to-model tracking on TUM fr3/teddy (193 frames) with the default
// tracker must stay within 10 mm ATE of the motion-capture ground truth (InfiniTAM v3's robust
// tracker reaches 6.4 mm here). The loop is the pipeline's: track against the raycast of the previous
// pose, fuse at the tracked pose, raycast from it. Coarse 1 cm voxels keep the dense CPU volume quick;
// at 5 mm the ATE is the same (the model is not what limits it).

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>

#include "voxfuse/core/Timer.h"
#include "voxfuse/engines/IntegrationEngine.h"
#include "voxfuse/engines/LowLevelEngine.h"
#include "voxfuse/engines/MainEngine.h"  // the pipeline's default depth gap tolerance
#include "voxfuse/engines/RaycastEngine.h"
#include "voxfuse/engines/Tracker.h"
#include "voxfuse/eval/TrajectoryError.h"
#include "voxfuse/io/ImageSource.h"
#include "voxfuse/objects/Voxel.h"

namespace voxfuse {
namespace {

TEST(TeddyTrackingTest, DefaultTrackerStaysWithinTenMillimetresAte) {
    const std::string dir = std::string(VOXFUSE_SHARED_DATA_DIR) + "/tum_fr3_teddy_200";
    if (!std::filesystem::exists(dir + "/rgb.txt")) GTEST_SKIP() << "../shared/data not found at " << dir << ": skipping the teddy test";

    auto source = openImageSource(dir);
    const RGBDCalib& calib = source->calib();
    SceneParams params;
    params.voxel_size_m = 0.01f;
    params.mu_m = 0.04f;
    Scene<VoxelS, PlainVoxelArray> scene(params, PlainVoxelArray({-128, -128, 0}, {256, 256, 256}), Device::CPU);
    auto low_level = makeLowLevelEngine(Device::CPU);
    auto integration = makeIntegrationEngine<VoxelS, PlainVoxelArray>(Device::CPU);
    auto raycast = makeRaycastEngine<VoxelS, PlainVoxelArray>(Device::CPU);
    auto tracker = makeTracker(TrackerSettings(), Device::CPU);

    View view;
    view.calib = calib;
    TrackingState tracking;  // the first camera defines the world
    RenderState model;
    std::vector<TimedPose> trajectory;
    RGBDFrame frame;
    int failed = 0, poor = 0;
    double track_ms = 0.0;
    while (source->next(frame)) {
        low_level->convertDepthToMetres(frame.depth_raw, calib.disparity, calib.depth.fx, params.view_frustum_min_m,
                                        params.view_frustum_max_m, MainEngineSettings{}.depth_gap_tolerance, view.depth);
        view.rgb.resize(frame.rgb.size());
        std::memcpy(static_cast<void*>(view.rgb.host()), frame.rgb.host(), frame.rgb.pixelCount() * sizeof(Vec4u8));
        const Timer t;
        tracker->track(tracking, view, model);
        track_ms += t.elapsedMs();
        failed += tracking.quality == TrackingQuality::Failed;
        poor += tracking.quality == TrackingQuality::Poor;
        if (tracking.quality != TrackingQuality::Failed) integration->integrate(scene, view, tracking.T_world_camera);
        raycast->raycast(scene, calib.depth, tracking.T_world_camera, model);
        trajectory.push_back({frame.timestamp_s, tracking.T_world_camera});
    }
    ASSERT_EQ(trajectory.size(), 193u);

    const TrajectoryError e = evaluateTrajectory(trajectory, source->groundTruth());
    std::printf("[ teddy    ] %s tracker: ATE RMSE %.2f mm (mean %.2f, median %.2f, max %.2f, %d pairs), RPE %.2f mm/s %.3f deg/s, "
                "track %.1f ms/frame, %d poor, %d failed\n",
                toString(tracker->settings().kind), 1000 * e.ate_rmse_m, 1000 * e.ate_mean_m, 1000 * e.ate_median_m, 1000 * e.ate_max_m,
                e.pairs, 1000 * e.rpe_trans_m_per_s, e.rpe_rot_deg_per_s, track_ms / double(trajectory.size()), poor, failed);
    EXPECT_EQ(failed, 0);
    EXPECT_GE(e.pairs, 185) << "ground truth starts at the 5th frame";
    EXPECT_LT(e.ate_rmse_m, 0.010);
    EXPECT_LT(e.ate_max_m, 0.025);
    EXPECT_LT(e.rpe_trans_m_per_s, 0.015);
}

// The pipeline as voxfuse runs it (5 mm s_rgb voxels) with the rgbd tracker, whose colour term aligns
// each frame to the map's fused colours (frame to model): on teddy 6.55 mm ATE, against 7.05 mm with
// the previous frame's colours (frame to frame, `color_from_map = false`) and 7.16 mm for ren, the
// default tracker; InfiniTAM v3's CPU build 6.61 mm on the same frames (DESIGN_NOTES).
TEST(TeddyTrackingTest, RgbdAlignedToTheMapsColoursBeatsDepthAlone) {
    const std::string dir = std::string(VOXFUSE_SHARED_DATA_DIR) + "/tum_fr3_teddy_200";
    if (!std::filesystem::exists(dir + "/rgb.txt")) GTEST_SKIP() << "../shared/data not found at " << dir << ": skipping the teddy test";
    auto source = openImageSource(dir);
    MainEngineSettings s;
    s.voxel_type = VoxelType::SRgb;  // voxfuse's default: the map has colours
    s.tracker.kind = TrackerKind::Rgbd;
    auto engine = MainEngine::create(s, source->calib());
    std::vector<TimedPose> trajectory;
    RGBDFrame frame;
    while (source->next(frame)) {
        const FrameResult r = engine->processFrame(frame, nullptr);
        EXPECT_EQ(r.status, TrackingStatus::Tracking) << "frame " << frame.index;
        trajectory.push_back({frame.timestamp_s, r.T_world_camera});
    }
    const TrajectoryError e = evaluateTrajectory(trajectory, source->groundTruth());
    std::printf("[ teddy    ] rgbd, map colours, 5 mm: ATE RMSE %.2f mm (max %.2f), RPE %.2f mm/s; %.2f mm at the best clock offset\n",
                1000 * e.ate_rmse_m, 1000 * e.ate_max_m, 1000 * e.rpe_trans_m_per_s, 1000 * e.ate_rmse_at_best_offset_m);
    EXPECT_EQ(trajectory.size(), 193u);
    EXPECT_LT(e.ate_rmse_m, 0.0068);
    EXPECT_LT(e.rpe_trans_m_per_s, 0.0080);
}

}  // namespace
}  // namespace voxfuse
