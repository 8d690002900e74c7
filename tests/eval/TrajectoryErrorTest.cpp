// ATE and RPE against hand-computed cases.

#include <gtest/gtest.h>

#include <cmath>

#include <Eigen/Geometry>

#include "voxfuse/core/EigenInterop.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/eval/TrajectoryError.h"

namespace voxfuse {
namespace {

Mat4f pose(const Eigen::Vector3f& t, float yaw_deg = 0.f, const Eigen::Vector3f& axis = Eigen::Vector3f::UnitZ()) {
    Eigen::Matrix4f T = Eigen::Matrix4f::Identity();
    T.topLeftCorner<3, 3>() =
        Eigen::AngleAxisf(yaw_deg * float(EIGEN_PI) / 180.f, axis.normalized()).toRotationMatrix();
    T.topRightCorner<3, 1>() = t;
    return toMat4f(T);
}

// An arbitrary rigid transform between the estimate's world and the ground truth's.
const Mat4f kWorldOffset = pose({1.5f, -2.f, 0.7f}, 40.f, {0.3f, -0.5f, 1.f});

TEST(TrajectoryErrorTest, RigidOffsetPlusKnownErrorsGivesTheExpectedAte) {
    // Two squares of positions (z = 0 and z = 1) with errors along z of +-d1 and +-d2. The signs make
    // the errors sum to zero and uncorrelated with the positions, so the best alignment is exactly
    // the world offset and the aligned errors are exactly d1 and d2.
    const float d1 = 0.01f, d2 = 0.03f;
    const Eigen::Vector3f corners[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    const float sign[4] = {1, -1, 1, -1};
    std::vector<TimedPose> truth, estimate;
    for (int square = 0; square < 2; ++square)
        for (int k = 0; k < 4; ++k) {
            const double t = 0.1 * (4 * square + k);
            const Eigen::Vector3f p = corners[k] * (1.f + square) + Eigen::Vector3f(0, 0, float(square));
            const float d = square == 0 ? d1 : d2;
            truth.push_back({t, pose(p, 30.f * float(k))});
            const Mat4f measured = pose(p + Eigen::Vector3f(0, 0, sign[k] * d), 30.f * float(k) + 5.f);
            estimate.push_back({t + 0.005, rigidInverse(kWorldOffset) * measured});  // 5 ms clock offset: still paired
        }
    const TrajectoryError e = evaluateTrajectory(estimate, truth);
    EXPECT_EQ(e.pairs, 8);
    EXPECT_NEAR(e.ate_rmse_m, std::sqrt((4.0 * d1 * d1 + 4.0 * d2 * d2) / 8.0), 1e-5);
    EXPECT_NEAR(e.ate_mean_m, (d1 + d2) / 2.0, 1e-5);
    EXPECT_NEAR(e.ate_median_m, (d1 + d2) / 2.0, 1e-5);
    EXPECT_NEAR(e.ate_max_m, d2, 1e-5);
    for (int k = 0; k < 16; ++k)
        EXPECT_NEAR(e.T_truth_estimate.m[k], kWorldOffset.m[k], 1e-4) << "alignment entry " << k;
}

TEST(TrajectoryErrorTest, PosesFartherThanTwentyMillisecondsAreNotPaired) {
    std::vector<TimedPose> truth, estimate;
    for (int i = 0; i < 10; ++i) {
        truth.push_back({0.1 * i, pose({0.1f * i, 0.05f * i * i, 0.f})});
        estimate.push_back({0.1 * i, truth.back().T_world_camera});
    }
    // Wild estimates 30 ms from any ground truth: pairing them would ruin the error.
    for (int i = 0; i < 9; ++i) estimate.push_back({0.1 * i + 0.03, pose({5.f, 5.f, 5.f})});
    const TrajectoryError e = evaluateTrajectory(estimate, truth);
    EXPECT_EQ(e.pairs, 10);
    EXPECT_NEAR(e.ate_rmse_m, 0.0, 1e-6);
    EXPECT_NEAR(e.ate_max_m, 0.0, 1e-6);

    TrajectoryErrorOptions loose;
    loose.max_time_difference_s = 0.04;
    EXPECT_EQ(evaluateTrajectory(estimate, truth, loose).pairs, 19);
}

TEST(TrajectoryErrorTest, TooFewPairsGiveNaN) {
    const std::vector<TimedPose> truth = {{0.0, pose({0, 0, 0})}, {1.0, pose({1, 0, 0})}};
    const TrajectoryError e = evaluateTrajectory(truth, truth);
    EXPECT_EQ(e.pairs, 2);
    EXPECT_TRUE(std::isnan(e.ate_rmse_m));
}

TEST(TrajectoryErrorTest, RpeMeasuresTranslationalDriftPerSecond) {
    // Ground truth moves at 0.10 m/s along x, the estimate at 0.11 m/s (and in another world frame):
    // every 1 s relative motion is 1 cm too long.
    std::vector<TimedPose> truth, estimate;
    for (int i = 0; i <= 30; ++i) {
        const double t = 0.1 * i;
        truth.push_back({t, pose({0.10f * float(t), 0.f, 0.f}, 20.f)});
        estimate.push_back({t, kWorldOffset * pose({0.11f * float(t), 0.f, 0.f}, 20.f)});
    }
    const TrajectoryError e = evaluateTrajectory(estimate, truth);
    EXPECT_EQ(e.rpe_pairs, 21) << "pairs (i, i + 1 s) for t_i = 0 .. 2 s";
    EXPECT_NEAR(e.rpe_trans_m_per_s, 0.01, 1e-5);
    EXPECT_NEAR(e.rpe_rot_deg_per_s, 0.0, 1e-2);
}

TEST(TrajectoryErrorTest, RpeMeasuresRotationalDriftPerSecond) {
    // Both rotate in place about z; the estimate turns 1 degree per second faster.
    std::vector<TimedPose> truth, estimate;
    for (int i = 0; i <= 30; ++i) {
        const double t = 0.1 * i;
        truth.push_back({t, pose({0.f, 0.f, 0.f}, 10.f * float(t))});
        estimate.push_back({t, pose({0.f, 0.f, 0.f}, 11.f * float(t))});
    }
    const TrajectoryError e = evaluateTrajectory(estimate, truth);
    EXPECT_EQ(e.rpe_pairs, 21);
    EXPECT_NEAR(e.rpe_rot_deg_per_s, 1.0, 1e-2);
    EXPECT_NEAR(e.rpe_trans_m_per_s, 0.0, 1e-6);
}

// A path on which a time shift is no rigid motion: x = t, y = 0.3 sin(2t), z = 0.1 t^2 (m, s).
Mat4f curvedPathPose(double t) {
    return pose({float(t), 0.3f * float(std::sin(2.0 * t)), 0.1f * float(t * t)}, 15.f * float(t));
}

TEST(TrajectoryErrorTest, TheBestTimeOffsetUndoesAClockThatLags) {
    // Ground truth at 100 Hz; the camera at 25 Hz on its grid, its poses exact but stamped 30 ms late.
    std::vector<TimedPose> truth, estimate;
    for (int i = 0; i <= 500; ++i) truth.push_back({0.01 * i, curvedPathPose(0.01 * i)});
    for (int i = 5; i < 120; ++i) estimate.push_back({0.04 * i + 0.03, kWorldOffset * curvedPathPose(0.04 * i)});
    const TrajectoryError e = evaluateTrajectory(estimate, truth);
    EXPECT_EQ(e.pairs, 115);
    EXPECT_GT(e.ate_rmse_m, 0.005) << "the lag costs several millimetres";
    EXPECT_NEAR(e.best_time_offset_s, -0.030, 1e-9) << "offsets of -34..-26 ms all pair each pose with its own time";
    EXPECT_NEAR(e.ate_rmse_at_best_offset_m, 0.0, 1e-5);

    TrajectoryErrorOptions shifted;  // the offset given: the ATE and RPE at it, the search around it
    shifted.time_offset_s = -0.03;
    const TrajectoryError at = evaluateTrajectory(estimate, truth, shifted);
    EXPECT_NEAR(at.ate_rmse_m, 0.0, 1e-5);
    EXPECT_NEAR(at.rpe_trans_m_per_s, 0.0, 1e-5);
    EXPECT_NEAR(at.best_time_offset_s, -0.030, 1e-9);

    // -30 ms lies outside +-20 ms: the best within pairs each pose with the ground truth 10 ms
    // after its time, as every offset of -20..-16 ms does; the middle of those.
    TrajectoryErrorOptions narrow;
    narrow.max_time_offset_s = 0.02;
    EXPECT_NEAR(evaluateTrajectory(estimate, truth, narrow).best_time_offset_s, -0.018, 1e-9);
    TrajectoryErrorOptions off;
    off.max_time_offset_s = 0.0;
    EXPECT_TRUE(std::isnan(evaluateTrajectory(estimate, truth, off).best_time_offset_s));
    TrajectoryErrorOptions wide;
    wide.max_time_offset_s = 1e9;  // a billion steps: refused, not run
    EXPECT_THROW(evaluateTrajectory(estimate, truth, wide), ConfigError);
    TrajectoryErrorOptions nan_offset;
    nan_offset.time_offset_s = std::nan("");
    EXPECT_THROW(evaluateTrajectory(estimate, truth, nan_offset), ConfigError);
}

TEST(TrajectoryErrorTest, OffsetsThatLoseMoreThanAFewPairsAreNoCandidates) {
    // Up to 1.6 s: ground truth at 100 Hz and exact poses 40 ms apart. After it: poses 80 ms apart,
    // 5 m off, and ground truth only at their times. An offset of 21-59 ms leaves those 10 of 50
    // without a partner (the rest pair with ground truth that much later, a few centimetres off),
    // which would score far better than any offset that keeps them.
    std::vector<TimedPose> truth, estimate;
    for (int i = 0; i < 160; ++i) truth.push_back({0.01 * i, curvedPathPose(0.01 * i)});
    for (int k = 0; k < 40; ++k) estimate.push_back({0.04 * k, kWorldOffset * curvedPathPose(0.04 * k)});
    for (int j = 0; j < 10; ++j) {
        const double t = 1.6 + 0.08 * j;
        truth.push_back({t, curvedPathPose(t)});
        Mat4f wild = curvedPathPose(t);
        wild.m[3] += 5.f;  // x
        estimate.push_back({t, kWorldOffset * wild});
    }
    const TrajectoryError e = evaluateTrajectory(estimate, truth);
    EXPECT_EQ(e.pairs, 50);
    EXPECT_GT(e.ate_rmse_m, 1.0);
    EXPECT_GT(e.ate_rmse_at_best_offset_m, 1.0) << "best at " << e.best_time_offset_s << " s";
    TrajectoryErrorOptions at_30ms;
    at_30ms.time_offset_s = 0.03;
    at_30ms.max_time_offset_s = 0.0;
    const TrajectoryError dropped = evaluateTrajectory(estimate, truth, at_30ms);
    EXPECT_EQ(dropped.pairs, 40);
    EXPECT_LT(dropped.ate_rmse_m, 0.1) << "what the offset would have scored";
}

TEST(TrajectoryErrorTest, AnOffsetMayLeaveAPoseOfAGapInTheGroundTruthUnpaired) {
    // Poses 50 ms apart, exact but stamped 30 ms late; ground truth at 100 Hz but for 1.98-2.02 s.
    // At the best offset the pose stamped 2.03 s has no partner (nearest 30 ms away), where at 0 it
    // has: one pose fewer is allowed, so the offset is found all the same.
    std::vector<TimedPose> truth, estimate;
    for (int i = 0; i <= 500; ++i)
        if (i < 198 || i > 202) truth.push_back({0.01 * i, curvedPathPose(0.01 * i)});
    for (int k = 2; k < 90; ++k) estimate.push_back({0.05 * k + 0.03, kWorldOffset * curvedPathPose(0.05 * k)});
    const TrajectoryError e = evaluateTrajectory(estimate, truth);
    EXPECT_EQ(e.pairs, 88);
    EXPECT_NEAR(e.best_time_offset_s, -0.030, 1e-9);
    EXPECT_NEAR(e.ate_rmse_at_best_offset_m, 0.0, 1e-5);
    const std::vector<TimedPose> two(truth.begin(), truth.begin() + 2);
    EXPECT_TRUE(std::isnan(evaluateTrajectory(two, truth).best_time_offset_s)) << "too few pairs";
}

}  // namespace
}  // namespace voxfuse
