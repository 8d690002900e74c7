#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "IoTestUtil.h"
#include "voxfuse/core/EigenInterop.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/TrajectoryIO.h"

namespace voxfuse {
namespace {

using test::readBytes;
using test::ScratchDir;
using test::writeBytes;

Mat4f pose(const Eigen::Vector3f& axis, float angle_rad, const Eigen::Vector3f& t) {
    Eigen::Matrix4f T = Eigen::Matrix4f::Identity();
    T.topLeftCorner<3, 3>() = Eigen::AngleAxisf(angle_rad, axis.normalized()).toRotationMatrix();
    T.topRightCorner<3, 1>() = t;
    return toMat4f(T);
}

void expectPoseNear(const Mat4f& a, const Mat4f& b, float tolerance) {
    for (int i = 0; i < 16; ++i) EXPECT_NEAR(a.m[i], b.m[i], tolerance) << "element " << i;
}

TEST(TrajectoryIO, ReadsPosesAndNormalisesQuaternions) {
    ScratchDir dir;
    const std::string path = dir.file("traj.txt");
    const double s = std::sqrt(0.5);
    // Second pose: 90 degrees about z, quaternion written at twice unit length.
    writeBytes(path,
               "# timestamp tx ty tz qx qy qz qw\n\n"
               "1341841873.4151 1 2 3 0 0 0 1\n"
               "1341841873.4251 -2.5 0 0.5 0 0 " +
                   std::to_string(2 * s) + " " + std::to_string(2 * s) + "\n");
    const std::vector<TimedPose> poses = readTumTrajectory(path);
    ASSERT_EQ(poses.size(), 2u);
    EXPECT_DOUBLE_EQ(poses[0].timestamp_s, 1341841873.4151);
    expectPoseNear(poses[0].T_world_camera, pose({0, 0, 1}, 0.f, {1, 2, 3}), 1e-6f);
    expectPoseNear(poses[1].T_world_camera, pose({0, 0, 1}, float(M_PI / 2), {-2.5f, 0.f, 0.5f}), 1e-5f);
    // Maps the camera's x axis onto the world's y axis.
    EXPECT_NEAR(poses[1].T_world_camera(1, 0), 1.f, 1e-5f);
}

TEST(TrajectoryIO, MalformedLinesNameTheLine) {
    struct Case {
        const char* what;
        std::string third_line;
        const char* reason_part;
    };
    const std::vector<Case> cases = {
        {"seven numbers", "2.0 0 0 0 0 0 1", "expected 8 numbers"},
        {"nine numbers", "2.0 0 0 0 0 0 0 1 5", "expected 8 numbers"},
        {"non-number", "2.0 0 0 zero 0 0 0 1", "not a number: 'zero'"},
        {"infinite value", "2.0 inf 0 0 0 0 0 1", "non-finite"},
        {"zero quaternion", "2.0 0 0 0 0 0 0 0", "zero-length quaternion"},
        {"time going back", "0.5 0 0 0 0 0 0 1", "timestamps must not decrease"},
        {"position finite as a double, infinite as a float", "2.0 1e39 0 0 0 0 0 1", "non-finite position '1e39'"},
        {"quaternion infinite as a float", "2.0 0 0 0 0 0 4e38 1", "non-finite quaternion"},
        {"one time, two poses", "1.0 0.5 0 0 0 0 0 1", "timestamp 1.0 is given twice (line 2) with different poses"},
    };
    ScratchDir dir;
    for (const Case& c : cases) {
        SCOPED_TRACE(c.what);
        const std::string path = dir.file("bad.txt");
        writeBytes(path, "# header\n1.0 0 0 0 0 0 0 1\n" + c.third_line + "\n");
        try {
            readTumTrajectory(path);
            ADD_FAILURE() << "no ParseError";
        } catch (const ParseError& e) {
            EXPECT_EQ(e.line(), 3) << e.what();
            EXPECT_NE(std::string(e.what()).find(path + ":3"), std::string::npos) << e.what();
            EXPECT_NE(e.reason().find(c.reason_part), std::string::npos) << e.what();
        }
    }
}

TEST(TrajectoryIO, ARepeatedIdenticalSampleIsKeptOnce) {
    ScratchDir dir;
    const std::string path = dir.file("traj.txt");
    writeBytes(path, "1.0 1 2 3 0 0 0 1\n1.0 1 2 3 0 0 0 1\n2.0 1 2 3 0 0 0 1\n");
    EXPECT_EQ(readTumTrajectory(path).size(), 2u);
}

TEST(TrajectoryIO, MissingFileIsAnIoError) {
    EXPECT_THROW(readTumTrajectory("/nonexistent/voxfuse/traj.txt"), IoError);
    EXPECT_THROW(writeTumTrajectory("/nonexistent/voxfuse/traj.txt", {}), IoError);
}

TEST(TrajectoryIO, WriteThenReadRoundTrip) {
    ScratchDir dir;
    std::vector<TimedPose> poses;
    for (int i = 0; i < 20; ++i) {
        const float angle = -3.f + 0.31f * float(i);  // includes rotations past 180 degrees' worth of sign flips
        poses.push_back({1341841873.273798 + 0.033 * i,
                         pose({0.3f * float(i) - 2.f, 1.f, 0.5f}, angle, {0.1f * float(i), -1.234567f, 12.5f})});
    }
    const std::string path = dir.file("traj.txt");
    writeTumTrajectory(path, poses);
    const std::vector<TimedPose> back = readTumTrajectory(path);
    ASSERT_EQ(back.size(), poses.size());
    for (std::size_t i = 0; i < poses.size(); ++i) {
        SCOPED_TRACE(i);
        EXPECT_NEAR(back[i].timestamp_s, poses[i].timestamp_s, 1e-6);
        expectPoseNear(back[i].T_world_camera, poses[i].T_world_camera, 2e-6f);
    }
    // Six decimals for time, as TUM's own files.
    const std::string text = readBytes(path);
    EXPECT_NE(text.find("\n1341841873.273798 "), std::string::npos) << text.substr(0, 200);
}

TEST(TrajectoryIO, InterpolatesBetweenSamples) {
    const std::vector<TimedPose> poses = {{10.00, pose({0, 0, 1}, 0.f, {0, 0, 0})},
                                          {10.01, pose({0, 0, 1}, float(M_PI / 2), {1, 2, -4})}};
    Mat4f T;
    ASSERT_TRUE(interpolatePose(poses, 10.005, 0.02, T));
    expectPoseNear(T, pose({0, 0, 1}, float(M_PI / 4), {0.5f, 1.f, -2.f}), 1e-4f);

    ASSERT_TRUE(interpolatePose(poses, 10.0025, 0.02, T));
    expectPoseNear(T, pose({0, 0, 1}, float(M_PI / 8), {0.25f, 0.5f, -1.f}), 1e-4f);

    ASSERT_TRUE(interpolatePose(poses, 10.00, 0.02, T));  // exact sample, exactly
    for (int i = 0; i < 16; ++i) EXPECT_EQ(T.m[i], poses[0].T_world_camera.m[i]);
}

TEST(TrajectoryIO, FallsBackToNearestSampleWithinGap) {
    const std::vector<TimedPose> poses = {{1.0, pose({0, 0, 1}, 0.f, {0, 0, 0})},
                                          {2.0, pose({1, 0, 0}, 1.f, {5, 5, 5})}};
    Mat4f T;
    ASSERT_TRUE(interpolatePose(poses, 1.01, 0.02, T));  // next sample is a second away: no interpolation
    expectPoseNear(T, poses[0].T_world_camera, 0.f);
    ASSERT_TRUE(interpolatePose(poses, 1.99, 0.02, T));
    expectPoseNear(T, poses[1].T_world_camera, 0.f);
    ASSERT_TRUE(interpolatePose(poses, 2.015, 0.02, T));  // after the end
    expectPoseNear(T, poses[1].T_world_camera, 0.f);
    ASSERT_TRUE(interpolatePose(poses, 0.99, 0.02, T));  // before the start
    expectPoseNear(T, poses[0].T_world_camera, 0.f);
    EXPECT_FALSE(interpolatePose(poses, 1.5, 0.02, T));
    EXPECT_FALSE(interpolatePose(poses, 0.5, 0.02, T));
    EXPECT_FALSE(interpolatePose(poses, 2.5, 0.02, T));
    EXPECT_FALSE(interpolatePose({}, 1.0, 0.02, T));
}

}  // namespace
}  // namespace voxfuse
