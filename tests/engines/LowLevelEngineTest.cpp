// Low-level image operations against hand-computed values.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "DeviceTestSupport.h"
#include "SyntheticViews.h"
#include "voxfuse/engines/LowLevelEngine.h"
#include "voxfuse/shared/LowLevel.h"

namespace voxfuse {
namespace {

TEST(LowLevelEngineTest, ConvertsAffineAndKinectDepth) {
    auto engine = makeLowLevelEngine(Device::CPU);
    Image<std::uint16_t> raw({4, 1});
    raw.host()[0] = 0;
    raw.host()[1] = 5000;
    raw.host()[2] = 10000;
    raw.host()[3] = 60000;
    Image<float> depth;
    engine->convertDepthToMetres(raw, DisparityCalib::affine(0.0002f), 525.f, 0.2f, 5.0f, 0.f, depth);
    EXPECT_EQ(depth.host()[0], 0.f);
    EXPECT_FLOAT_EQ(depth.host()[1], 1.0f);
    EXPECT_FLOAT_EQ(depth.host()[2], 2.0f);
    EXPECT_EQ(depth.host()[3], 0.f) << "12 m is beyond the 5 m limit";

    // Kinect: depth = 8 * k2 * fx / (k1 - raw).
    const DisparityCalib kinect = DisparityCalib::kinect(1135.09f, 0.0819141f);
    raw.host()[1] = 800;
    raw.host()[2] = 1135;  // k1 - raw ~ 0: effectively infinite depth
    engine->convertDepthToMetres(raw, kinect, 573.71f, 0.2f, 10.f, 0.f, depth);
    EXPECT_NEAR(depth.host()[1], 8.f * 0.0819141f * 573.71f / (1135.09f - 800.f), 1e-5f);
    EXPECT_EQ(depth.host()[2], 0.f);
}

// One-pixel gaps between two agreeing neighbours are filled with their mean, left-right first, then
// up-down; wider gaps, gaps at a depth edge, gaps beside a sample out of range and range-rejected
// samples themselves stay empty. Depth in metres below is raw / 5000 (0 = no measurement).
class LowLevelDeviceTest : public ::testing::TestWithParam<Device> {};

TEST_P(LowLevelDeviceTest, FillsOnePixelGapsBetweenAgreeingNeighbours) {
    VF_SKIP_IF_UNAVAILABLE(GetParam());
    auto engine = makeLowLevelEngine(GetParam());
    const float metres[5][5] = {{1.00f, 0.f, 1.01f, 0.f, 2.00f},
                                {0.f, 0.f, 1.00f, 1.00f, 1.00f},
                                {1.00f, 0.f, 0.f, 1.00f, 9.00f},
                                {1.00f, 1.00f, 1.04f, 0.f, 0.f},
                                {0.f, 1.00f, 9.00f, 1.00f, 0.f}};
    Image<std::uint16_t> raw({5, 5});
    for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 5; ++x) raw.at(x, y) = std::uint16_t(std::lround(metres[y][x] * 5000.f));
    const DisparityCalib calib = DisparityCalib::affine(0.0002f);
    const auto metresOf = [&](float m) { return calib.toMetres(std::uint16_t(std::lround(m * 5000.f)), 525.f); };
    Image<float> depth;
    engine->convertDepthToMetres(raw, calib, 525.f, 0.2f, 5.f, 0.02f, depth);
    depth.memory().updateHost();
    const Image<float>& filled = depth;
    EXPECT_FLOAT_EQ(filled.at(1, 0), 0.5f * (metresOf(1.00f) + metresOf(1.01f))) << "left and right agree within 2%";
    EXPECT_EQ(filled.at(3, 0), 0.f) << "a depth edge (1.01 | 2.00 m) on the top row: not bridged";
    EXPECT_FLOAT_EQ(filled.at(0, 1), metresOf(1.00f)) << "the left column: filled from above and below";
    EXPECT_EQ(filled.at(1, 1), 0.f) << "a gap two pixels wide";
    EXPECT_EQ(filled.at(1, 2), 0.f) << "only one side measured";
    EXPECT_EQ(filled.at(2, 2), 0.f) << "above and below differ by 4%";
    EXPECT_FLOAT_EQ(filled.at(3, 3), metresOf(1.00f)) << "left-right fails (a gap on the right), up-down agrees";
    EXPECT_EQ(filled.at(4, 3), 0.f) << "the sample above is beyond the 5 m limit";
    EXPECT_EQ(filled.at(2, 4), 0.f) << "a measured sample out of range stays empty";
    EXPECT_EQ(filled.at(4, 2), 0.f);
    EXPECT_FLOAT_EQ(filled.at(2, 3), metresOf(1.04f)) << "measured samples are kept as measured";

    engine->convertDepthToMetres(raw, calib, 525.f, 0.2f, 5.f, 0.f, depth);
    depth.memory().updateHost();
    const Image<float>& kept = depth;
    for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 5; ++x)
            EXPECT_EQ(kept.at(x, y), metres[y][x] > 0.f && metres[y][x] <= 5.f ? metresOf(metres[y][x]) : 0.f)
                << x << "," << y << ": tolerance 0 fills nothing";
}

// A subsampled tracker level reads every second (third) pixel: its packed points and normals are the
// full maps' at those pixels, bit for bit, on either device (holes and edges included).
TEST_P(LowLevelDeviceTest, PackedGridPointsAndNormalsAreTheFullMapsThere) {
    VF_SKIP_IF_UNAVAILABLE(GetParam());
    auto cpu = makeLowLevelEngine(Device::CPU);
    auto engine = makeLowLevelEngine(GetParam());
    const Intrinsics intr = test::kinectIntrinsics(161, 121);
    Image<float> depth(intr.size());
    for (int y = 0; y < intr.height; ++y)
        for (int x = 0; x < intr.width; ++x)
            depth.at(x, y) =
                (x + y) % 7 == 0 ? 0.f : 1.f + 0.002f * float((x * 7 + y * 13) % 11) + (x > 90 ? 0.3f : 0.f);
    Image<Vec4f> vertices, full;
    cpu->computeVertexMap(depth, intr, vertices);
    cpu->computeNormalMap(vertices, full, 0.1f);
    for (int step : {1, 2, 3}) {
        Image<Vec4f> points, normals;
        engine->computeGridPointsAndNormals(depth, intr, 0.1f, step, points, normals);
        points.memory().updateHost();
        normals.memory().updateHost();
        const Vec2i grid{(intr.width + step - 1) / step, (intr.height + step - 1) / step};  // by hand, not gridExtent
        ASSERT_EQ(points.size(), grid);
        ASSERT_EQ(normals.size(), grid);
        int valid_normals = 0;
        for (int gy = 0; gy < grid.y; ++gy)
            for (int gx = 0; gx < grid.x; ++gx) {
                const Vec4f p = points.at(gx, gy), fp = vertices.at(gx * step, gy * step);
                const Vec4f n = normals.at(gx, gy), fn = full.at(gx * step, gy * step);
                EXPECT_TRUE(p.x == fp.x && p.y == fp.y && p.z == fp.z && p.w == fp.w)
                    << "point " << gx << "," << gy << ", step " << step;
                EXPECT_TRUE(n.x == fn.x && n.y == fn.y && n.z == fn.z && n.w == fn.w)
                    << "normal " << gx << "," << gy << ", step " << step;
                valid_normals += n.w > 0.f;
            }
        EXPECT_GT(valid_normals, grid.x * grid.y / 2) << "step " << step;
    }
    Image<Vec4f> points, normals;
    EXPECT_THROW(engine->computeGridPointsAndNormals(depth, intr, 0.1f, 0, points, normals), Error);
}

INSTANTIATE_TEST_SUITE_P(Devices, LowLevelDeviceTest, test::kAllDevices, test::DeviceName());

TEST(LowLevelEngineTest, BilateralFilterKeepsPlanesAndEdges) {
    auto engine = makeLowLevelEngine(Device::CPU);
    Image<float> depth({20, 10}), filtered;
    for (int y = 0; y < 10; ++y)
        for (int x = 0; x < 20; ++x) depth.at(x, y) = x < 10 ? 1.0f : 2.0f;  // a step edge
    depth.at(3, 3) = 0.f;                                                    // a hole
    engine->bilateralFilterDepth(depth, filtered, BilateralFilterParams{});
    EXPECT_EQ(filtered.at(3, 3), 0.f) << "holes stay holes";
    EXPECT_NEAR(filtered.at(9, 5), 1.0f, 1e-4f) << "the edge is not smeared";
    EXPECT_NEAR(filtered.at(10, 5), 2.0f, 1e-4f);
    EXPECT_NEAR(filtered.at(5, 5), 1.0f, 1e-6f);
}

// KinectFusion's filter written plainly, with the library's exp: the reference for the engine's
// separable spatial weights and inline exponential.
float referenceBilateral(const Image<float>& depth, int x, int y, const BilateralFilterParams& p) {
    const float centre = depth.at(x, y);
    if (!(centre > 0.f)) return 0.f;
    double sum = 0.0, weights = 0.0;
    for (int dy = -p.radius_px; dy <= p.radius_px; ++dy)
        for (int dx = -p.radius_px; dx <= p.radius_px; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= depth.width() || yy >= depth.height() || !(depth.at(xx, yy) > 0.f)) continue;
            const double diff = depth.at(xx, yy) - centre;
            const double w = std::exp(-double(dx * dx + dy * dy) / (2.0 * p.sigma_space_px * p.sigma_space_px) -
                                      diff * diff / (2.0 * p.sigma_depth_m * p.sigma_depth_m));
            sum += w * depth.at(xx, yy);
            weights += w;
        }
    return float(sum / weights);
}

TEST(LowLevelEngineTest, BilateralFilterMatchesTheFilterWrittenPlainly) {
    auto engine = makeLowLevelEngine(Device::CPU);
    Image<float> depth({64, 48}), filtered;
    // A slanted surface with ripples of a few centimetres (within the range sigma), a step, and holes.
    for (int y = 0; y < depth.height(); ++y)
        for (int x = 0; x < depth.width(); ++x)
            depth.at(x, y) = (x % 7 == 3 && y % 5 == 1)
                                 ? 0.f
                                 : 1.f + 0.01f * x + 0.03f * std::sin(0.9f * x + 1.7f * y) + (y > 30 ? 0.4f : 0.f);
    for (const BilateralFilterParams p :
         {BilateralFilterParams{}, BilateralFilterParams{5, 3.f, 0.02f}, BilateralFilterParams{0, 1.f, 0.01f}}) {
        engine->bilateralFilterDepth(depth, filtered, p);
        double worst = 0.0;
        for (int y = 0; y < depth.height(); ++y)
            for (int x = 0; x < depth.width(); ++x)
                worst = std::max(worst, double(std::fabs(filtered.at(x, y) - referenceBilateral(depth, x, y, p))));
        EXPECT_LT(worst, 2e-6) << "radius " << p.radius_px;
    }
    BilateralFilterParams too_wide;
    too_wide.radius_px = kMaxBilateralRadius + 1;
    EXPECT_THROW(engine->bilateralFilterDepth(depth, filtered, too_wide), ConfigError);
}

TEST(LowLevelEngineTest, ValidDepthIsCountedOnEveryPixelOrOnAGrid) {
    auto engine = makeLowLevelEngine(Device::CPU);
    Image<float> depth({5, 3});
    for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 5; ++x)
            depth.at(x, y) = (x + y) % 3 == 0 ? 0.f : 1.f;  // zeros at (0,0) (3,0) (2,1) (1,2) (4,2)
    EXPECT_EQ(engine->countValidDepth(depth), 10);
    // Columns 0, 2, 4 of rows 0 and 2: (0,0) and (4,2) are empty.
    EXPECT_EQ(engine->countValidDepth(depth, 2), 4);
    EXPECT_EQ(engine->countValidDepth(depth, 8), 0) << "only (0, 0)";
}

TEST(LowLevelEngineTest, DepthsBeyondTheLimitBecomeHoles) {
    auto engine = makeLowLevelEngine(Device::CPU);
    const float v[4] = {0.5f, 2.5f, 2.5001f, 0.f};
    Image<float> depth({4, 1});
    for (int i = 0; i < 4; ++i) depth.host()[i] = v[i];
    engine->dropDepthBeyond(depth, 2.5f);
    ASSERT_EQ(depth.size(), (Vec2i{4, 1}));
    EXPECT_EQ(depth.host()[0], 0.5f);
    EXPECT_EQ(depth.host()[1], 2.5f) << "the limit itself is kept";
    EXPECT_EQ(depth.host()[2], 0.f);
    EXPECT_EQ(depth.host()[3], 0.f);
    for (int i = 0; i < 4; ++i) depth.host()[i] = v[i];
    engine->dropDepthBeyond(depth, std::numeric_limits<float>::infinity());
    for (int i = 0; i < 4; ++i) EXPECT_EQ(depth.host()[i], v[i]) << "no limit: nothing changes";
}

TEST(LowLevelEngineTest, DownsampleAveragesValidSamplesOnOneSurface) {
    auto engine = makeLowLevelEngine(Device::CPU);
    Image<float> depth({4, 2}), half;
    const float v[8] = {1.0f, 1.2f, 0.f, 2.0f, 1.1f, 0.f, 0.f, 0.f};
    for (int i = 0; i < 8; ++i) depth.host()[i] = v[i];
    engine->downsampleDepth(depth, half, 0.25f);
    ASSERT_EQ(half.size(), (Vec2i{2, 1}));
    EXPECT_NEAR(half.host()[0], (1.0f + 1.2f + 1.1f) / 3.f, 1e-6f);
    EXPECT_NEAR(half.host()[1], 2.0f, 1e-6f);
}

TEST(LowLevelEngineTest, VertexAndNormalMapsOfATiltedPlane) {
    auto engine = makeLowLevelEngine(Device::CPU);
    const Intrinsics intr = test::kinectIntrinsics(160, 120);
    // Plane z = 1 + 0.5 x in camera coordinates: depth at pixel u is 1 / (1 - 0.5 (u - cx) / fx).
    Image<float> depth(intr.size());
    for (int y = 0; y < intr.height; ++y)
        for (int x = 0; x < intr.width; ++x) depth.at(x, y) = 1.f / (1.f - 0.5f * (float(x) - intr.cx) / intr.fx);
    Image<Vec4f> vertices, normals;
    engine->computeVertexMap(depth, intr, vertices);
    engine->computeNormalMap(vertices, normals, 0.1f);
    const Vec4f p = vertices.at(100, 50);
    EXPECT_NEAR(p.z, 1.f + 0.5f * p.x, 1e-5f);
    const Vec3f expected = normalize(Vec3f{0.5f, 0.f, -1.f});  // facing the camera
    const Vec4f n = normals.at(100, 50);
    ASSERT_EQ(n.w, 1.f);
    EXPECT_NEAR(dot(n.xyz(), expected), 1.f, 1e-4f);
    // Border pixels take one-sided differences: on a plane, the same normal.
    ASSERT_EQ(normals.at(0, 0).w, 1.f);
    EXPECT_NEAR(dot(normals.at(0, 0).xyz(), expected), 1.f, 1e-4f);
}

// Depth registered to another camera has empty rows and columns (here every 4th of each); the valid
// pixels beside them keep their normals (one-sided or across the gap), as on the full plane.
TEST(LowLevelEngineTest, HoleLinesDoNotTakeTheNormalsOfTheirNeighbours) {
    auto engine = makeLowLevelEngine(Device::CPU);
    const Intrinsics intr = test::kinectIntrinsics(160, 120);
    Image<float> depth(intr.size());
    for (int y = 0; y < intr.height; ++y)
        for (int x = 0; x < intr.width; ++x)
            depth.at(x, y) = (x % 4 == 3 || y % 4 == 3) ? 0.f : 1.f / (1.f - 0.5f * (float(x) - intr.cx) / intr.fx);
    Image<Vec4f> vertices, normals;
    engine->computeVertexMap(depth, intr, vertices);
    engine->computeNormalMap(vertices, normals, 0.1f);
    const Vec3f expected = normalize(Vec3f{0.5f, 0.f, -1.f});
    int valid = 0, with_normal = 0, right = 0;
    for (int y = 0; y < intr.height; ++y)
        for (int x = 0; x < intr.width; ++x) {
            const Vec4f n = normals.at(x, y);
            if (depth.at(x, y) <= 0.f) {
                EXPECT_EQ(n.w, 0.f) << "a pixel without depth has no normal";
                continue;
            }
            ++valid;
            with_normal += n.w > 0.f;
            right += n.w > 0.f && dot(n.xyz(), expected) > 1.f - 1e-4f;
        }
    EXPECT_EQ(with_normal, valid);
    EXPECT_EQ(right, valid);
}

// A depth edge is not bridged: pixels beside a step of more than the edge threshold get the normal of
// their own side.
TEST(LowLevelEngineTest, NormalsDoNotReachAcrossDepthEdges) {
    auto engine = makeLowLevelEngine(Device::CPU);
    const Intrinsics intr = test::kinectIntrinsics(160, 120);
    Image<float> depth(intr.size());
    for (int y = 0; y < intr.height; ++y)
        for (int x = 0; x < intr.width; ++x) depth.at(x, y) = x < 80 ? 1.f : 2.f;  // two fronto-parallel planes
    Image<Vec4f> vertices, normals;
    engine->computeVertexMap(depth, intr, vertices);
    engine->computeNormalMap(vertices, normals, 0.1f);
    for (int x : {78, 79, 80, 81}) {
        const Vec4f n = normals.at(x, 60);
        ASSERT_EQ(n.w, 1.f) << "x " << x;
        EXPECT_NEAR(n.z, -1.f, 1e-4f) << "x " << x << ": the normal of its own plane";
    }
}

}  // namespace
}  // namespace voxfuse
