#include <gtest/gtest.h>

#include <cmath>

#include "voxfuse/io/ArkitPose.h"

namespace voxfuse {
namespace {

void expectNear(Vec3f a, Vec3f b) {
    EXPECT_NEAR(a.x, b.x, 1e-5f);
    EXPECT_NEAR(a.y, b.y, 1e-5f);
    EXPECT_NEAR(a.z, b.z, 1e-5f);
}

TEST(ArkitPose, AnUnrotatedArkitCameraLooksDownTheWorldsMinusZ) {
    const Mat4f T = poseFromArkit({1.f, 2.f, 3.f}, {0.f, 0.f, 0.f, 1.f});
    const float expected[16] = {1, 0, 0, 1, 0, -1, 0, 2, 0, 0, -1, 3, 0, 0, 0, 1};
    for (int i = 0; i < 16; ++i) EXPECT_FLOAT_EQ(T.m[i], expected[i]) << "element " << i;
    // 1 m in front of our camera (our +z) is 1 m along ARKit's viewing direction, world -z.
    expectNear(transformPoint(T, {0.f, 0.f, 1.f}), {1.f, 2.f, 2.f});
    // Our image's "down" (+y) is the world's down (ARKit's world y is up).
    expectNear(transformDirection(T, {0.f, 1.f, 0.f}), {0.f, -1.f, 0.f});
}

TEST(ArkitPose, AQuarterTurnAboutTheVerticalTurnsTheViewToMinusX) {
    // 90 degrees about ARKit's world y (up): the camera's -z turns from world -z to world -x.
    const float s = std::sqrt(0.5f);
    const Mat4f T = poseFromArkit({0.5f, 0.f, 0.f}, {0.f, s, 0.f, s});
    expectNear(transformDirection(T, {0.f, 0.f, 1.f}), {-1.f, 0.f, 0.f});  // our viewing direction
    expectNear(transformDirection(T, {1.f, 0.f, 0.f}), {0.f, 0.f, -1.f});  // our image's right
    expectNear(transformDirection(T, {0.f, 1.f, 0.f}), {0.f, -1.f, 0.f});  // our image's down
    expectNear(transformPoint(T, {0.f, 0.f, 2.f}), {-1.5f, 0.f, 0.f});
}

TEST(ArkitPose, QuaternionsAreNormalisedAndTheResultIsARotation) {
    const Mat4f T = poseFromArkit({0.f, 0.f, 0.f}, {0.2f, -0.4f, 0.6f, 1.6f});  // norm 1.8
    const Mat3f R = T.rotation();
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            float dot = 0.f;
            for (int k = 0; k < 3; ++k) dot += R(i, k) * R(j, k);
            EXPECT_NEAR(dot, i == j ? 1.f : 0.f, 1e-5f);
        }
    const float det = R(0, 0) * (R(1, 1) * R(2, 2) - R(1, 2) * R(2, 1)) -
                      R(0, 1) * (R(1, 0) * R(2, 2) - R(1, 2) * R(2, 0)) +
                      R(0, 2) * (R(1, 0) * R(2, 1) - R(1, 1) * R(2, 0));
    EXPECT_NEAR(det, 1.f, 1e-5f);  // flipping two axes keeps it a proper rotation
}

}  // namespace
}  // namespace voxfuse
