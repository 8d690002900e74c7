// The submaps' overlay on the viewer's model panel (apps/viewer/SubmapOverlay.h): closed-form
// projections of submap origins into a panel that shows the render at half size.

#include <gtest/gtest.h>

#include "SubmapOverlay.h"

namespace voxfuse::viewer {
namespace {

Mat4f at(float x, float y, float z) {
    Mat4f T = Mat4f::identity();
    T.m[3] = x;
    T.m[7] = y;
    T.m[11] = z;
    return T;
}

TEST(SubmapOverlay, OriginsAndEdgesLandWhereTheRenderShowsThem) {
    const Intrinsics camera{640, 480, 500.f, 500.f, 319.5f, 239.5f};
    const PanelRect image{10, 20, 320, 240};  // the render at half size
    std::vector<SubmapPose> submaps{{at(0.f, 0.f, 2.f), -1}, {at(0.4f, 0.f, 2.f), 0}, {at(0.f, 0.f, -1.f), 1}};
    LoopClosure kept, rejected;
    kept.from_submap = 0;
    kept.to_submap = 1;
    rejected.from_submap = 1;
    rejected.to_submap = 0;
    rejected.rejected = true;
    const SubmapOverlay o = projectSubmaps(submaps, {kept, rejected}, Mat4f::identity(), camera, image);
    ASSERT_EQ(o.origins.size(), 2u) << "the submap behind the camera is left out";
    // The principal point's pixel (319.5) is the panel's middle; 0.4 m at 2 m is 100 pixels right, 50 in the panel.
    EXPECT_FLOAT_EQ(o.origins[0].x, 170.f);
    EXPECT_FLOAT_EQ(o.origins[0].y, 140.f);
    EXPECT_FLOAT_EQ(o.origins[1].x, 220.f);
    EXPECT_FLOAT_EQ(o.origins[1].y, 140.f);
    ASSERT_EQ(o.segments.size(), 2u) << "odometry 0-1 and the kept loop; the edge to the hidden submap and "
                                        "the rejected loop are not drawn";
    EXPECT_FALSE(o.segments[0].loop);
    EXPECT_TRUE(o.segments[1].loop);
    EXPECT_FLOAT_EQ(o.segments[1].to.x, 220.f);

    // Seen from 0.4 m to the right, the origins move left by 50 panel pixels.
    const SubmapOverlay moved = projectSubmaps(submaps, {}, at(0.4f, 0.f, 0.f), camera, image);
    ASSERT_EQ(moved.origins.size(), 2u);
    EXPECT_FLOAT_EQ(moved.origins[1].x, 170.f);
    EXPECT_FLOAT_EQ(moved.origins[0].x, 120.f);
}

}  // namespace
}  // namespace voxfuse::viewer
