// ATE and RPE against hand-computed cases.

#include <gtest/gtest.h>

#include <cmath>

#include <Eigen/Geometry>

#include "voxfuse/core/EigenInterop.h"
#include "voxfuse/eval/TrajectoryError.h"

namespace voxfuse {
namespace {

Mat4f pose(const Eigen::Vector3f& t, float yaw_deg = 0.f, const Eigen::Vector3f& axis = Eigen::Vector3f::UnitZ()) {
    Eigen::Matrix4f T = Eigen::Matrix4f::Identity();
    T.topLeftCorner<3, 3>() = Eigen::AngleAxisf(yaw_deg * float(EIGEN_PI) / 180.f, axis.normalized()).toRotationMatrix();
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
    for (int k = 0; k < 16; ++k) EXPECT_NEAR(e.T_truth_estimate.m[k], kWorldOffset.m[k], 1e-4) << "alignment entry " << k;
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

}  // namespace
}  // namespace voxfuse
