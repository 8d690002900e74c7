// The pose graph edges between submaps (engines/SubmapEdges.h): their uncertainty in closed form.

#include <gtest/gtest.h>

#include <cmath>

#include "TrackingTestSupport.h"
#include "engines/SubmapEdges.h"

namespace voxfuse {
namespace {

// The edges' uncertainty in closed form: odometry grows with the distance between the submaps'
// origins; a loop through a camera is a relocalisation's at both origins and adds each submap's drift
// between its origin and the camera.
TEST(SubmapEdgesTest, UncertaintyGrowsWithTheDistanceFromEachSubmapsOrigin) {
    constexpr float kDegree = float(M_PI) / 180.f;
    const Mat4f near = test::moveInCamera(Mat4f::identity(), {0.f, 1.f, 0.f}, 3.f, {0.1f, 0.f, 0.f});
    const Mat4f far = test::moveInCamera(Mat4f::identity(), {0.f, 1.f, 0.f}, 20.f, {0.9f, 0.f, 1.2f});  // 1.5 m
    const PoseGraphEdge short_hop = submap_edges::odometry(0, 1, near), long_hop = submap_edges::odometry(1, 2, far);
    EXPECT_FLOAT_EQ(short_hop.sigma_translation_m, 0.002f);  // the tracker's own noise
    EXPECT_FLOAT_EQ(short_hop.sigma_rotation_rad, 0.2f * kDegree);
    EXPECT_NEAR(long_hop.sigma_translation_m, 0.015f, 1e-6f);
    EXPECT_NEAR(long_hop.sigma_rotation_rad, 1.5f * kDegree, 1e-6f);
    EXPECT_FALSE(long_hop.loop);

    const PoseGraphEdge at_origins = submap_edges::loop(0, 3, Mat4f::identity(), Mat4f::identity());
    EXPECT_FLOAT_EQ(at_origins.sigma_translation_m, 0.005f);
    EXPECT_FLOAT_EQ(at_origins.sigma_rotation_rad, 0.5f * kDegree);
    EXPECT_TRUE(at_origins.loop);
    // The camera 0.1 m from submap 0's origin and 1.5 m from submap 3's: sqrt(5^2 + 1^2 + 15^2) mm.
    const PoseGraphEdge away = submap_edges::loop(0, 3, near, far);
    EXPECT_NEAR(away.sigma_translation_m, std::sqrt(25.f + 1.f + 225.f) * 1e-3f, 1e-6f);
    EXPECT_NEAR(away.sigma_rotation_rad, std::sqrt(0.25f + 0.01f + 2.25f) * kDegree, 1e-6f);
    // The measurement places submap 3 in submap 0 so that the camera is where both saw it.
    const Mat4f T_0_camera = away.T_from_to * far;
    for (int k = 0; k < 16; ++k) EXPECT_NEAR(T_0_camera.m[k], near.m[k], 1e-5f) << k;
}

}  // namespace
}  // namespace voxfuse
