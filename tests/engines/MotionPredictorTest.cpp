// Constant-velocity prediction: the last motion, scaled to the time since the last frame, and no
// prediction where the motion is unknown.

#include <gtest/gtest.h>

#include "engines/MotionPredictor.h"

namespace voxfuse {
namespace {

Mat4f poseAt(float x_m, float yaw_deg) {
    Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
    T.topLeftCorner<3, 3>() =
        Eigen::AngleAxisd(yaw_deg * EIGEN_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T(0, 3) = x_m;
    return pose::toMat4f(T);
}

double distanceM(const Eigen::Matrix4d& a, const Mat4f& b) {
    return (a.topRightCorner<3, 1>() - pose::toEigenD(b).topRightCorner<3, 1>()).norm();
}

TEST(MotionPredictorTest, TheLastMotionIsScaledToTheTimeSinceTheLastFrame) {
    MotionPredictor p;
    p.record(poseAt(0.00f, 0.f), {1.00, 0});
    p.record(poseAt(0.01f, 0.f), {1.10, 1});
    EXPECT_NEAR(distanceM(p.predict(poseAt(0.01f, 0.f), {1.20, 2}), poseAt(0.02f, 0.f)), 0.0, 1e-6)
        << "one interval on";
    EXPECT_NEAR(distanceM(p.predict(poseAt(0.01f, 0.f), {1.30, 3}), poseAt(0.03f, 0.f)), 0.0, 1e-6)
        << "a dropped frame: twice the motion";
    EXPECT_NEAR(distanceM(p.predict(poseAt(0.01f, 0.f), {1.50, 5}), poseAt(0.01f, 0.f)), 0.0, 1e-9)
        << "after a long gap: none";
    EXPECT_NEAR(distanceM(p.predict(poseAt(0.01f, 0.f), {1.10, 1}), poseAt(0.01f, 0.f)), 0.0, 1e-9)
        << "the same frame again: none";
    EXPECT_NEAR(distanceM(p.predict(poseAt(0.5f, 0.f), {1.20, 2}), poseAt(0.5f, 0.f)), 0.0, 1e-9)
        << "moved by the caller: none";
}

TEST(MotionPredictorTest, WithoutTimestampsFrameIndicesCount) {
    MotionPredictor p;
    p.record(poseAt(0.f, 0.f), {0.0, 4});
    p.record(poseAt(0.f, 2.f), {0.0, 5});
    const Eigen::Matrix4d predicted = p.predict(poseAt(0.f, 2.f), {0.0, 7});
    const Eigen::AngleAxisd rotation(Eigen::Matrix3d(predicted.topLeftCorner<3, 3>()));
    EXPECT_NEAR(rotation.angle() * 180.0 / EIGEN_PI, 6.0, 1e-4) << "two frames on: 2 degrees each";
}

// Relocalisation tracks one frame from several starts: the tries of one frame are no motion.
TEST(MotionPredictorTest, OneFrameRecordedTwiceIsOneFrame) {
    MotionPredictor p;
    p.record(poseAt(0.00f, 0.f), {1.0, 0});
    p.record(poseAt(0.30f, 0.f), {1.1, 1});  // a first try
    p.record(poseAt(0.01f, 0.f), {1.1, 1});  // the accepted one
    EXPECT_NEAR(distanceM(p.predict(poseAt(0.01f, 0.f), {1.2, 2}), poseAt(0.02f, 0.f)), 0.0, 1e-6);
    p.forget();
    p.record(poseAt(0.40f, 0.f), {1.3, 3});
    p.record(poseAt(0.41f, 0.f), {1.3, 3});
    EXPECT_NEAR(distanceM(p.predict(poseAt(0.41f, 0.f), {1.4, 4}), poseAt(0.41f, 0.f)), 0.0, 1e-9)
        << "one frame since forget(): no motion known";
}

}  // namespace
}  // namespace voxfuse
