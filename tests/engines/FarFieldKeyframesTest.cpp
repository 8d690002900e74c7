// rgbd's far field: a keyframe's far depths placed in the world with their colours (closed form), the
// points a later frame sees, and which keyframes are kept (engines/FarFieldKeyframes.h).

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "DeviceTestSupport.h"
#include "TrackingTestSupport.h"
#include "engines/FarFieldKeyframes.h"
#include "voxfuse/shared/ColorTrackerTerms.h"

namespace voxfuse {
namespace {

constexpr int kW = 64, kH = 48;
constexpr int kPlainColumns = 21;

Intrinsics smallCamera() { return Intrinsics{kW, kH, 50.f, 50.f, 31.5f, 23.5f}; }

// An intensity ramp I = 0.2 + a x (its Sobel gradient is (a, 0) away from the border).
std::vector<float> ramp(float a) {
    std::vector<float> image(kW * kH);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) image[std::size_t(x + y * kW)] = 0.2f + a * float(x);
    return image;
}

TEST(FarFieldPointTest, PlacesTheKeyframesDepthInTheWorldWithItsColor) {
    const Intrinsics cam = smallCamera();
    const std::vector<float> image = ramp(0.01f);
    std::vector<Vec2f> gradient(image.size());
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x)
            gradient[std::size_t(x + y * kW)] = sobelGradientPixel(image.data(), {kW, kH}, x, y);
    const Mat4f T_world_camera = test::moveInCamera(Mat4f::identity(), {0.f, 1.f, 0.f}, 30.f, {1.f, 2.f, 3.f});
    // The colour camera sits 5 cm to the side: the point is coloured where it sees it.
    const Mat4f T_rgb_depth = test::moveInCamera(Mat4f::identity(), {0.f, 1.f, 0.f}, 0.f, {-0.05f, 0.f, 0.f});
    const Mat4f T_rgb_world = T_rgb_depth * rigidInverse(T_world_camera);

    float gradient_sq = 0.f;
    const ColorPoint c = farFieldPoint(5.f, 20, 30, cam, T_world_camera, image.data(), gradient.data(), {kW, kH},
                                       T_rgb_world, cam, gradient_sq);
    const Vec3f expected =
        transformPoint(T_world_camera, Vec3f{(20.f - 31.5f) * 5.f / 50.f, (30.f - 23.5f) * 5.f / 50.f, 5.f});
    EXPECT_NEAR(length(c.p_world - expected), 0.f, 1e-5f);
    // Seen from the colour camera the pixel moves by f * (-0.05 m) / 5 m = -0.5 px in x.
    EXPECT_NEAR(c.intensity, 0.2f + 0.01f * 19.5f, 1e-5f);
    EXPECT_NEAR(gradient_sq, 0.01f * 0.01f, 1e-8f);

    // No depth, or a point the colour camera does not see: no colour.
    EXPECT_LT(farFieldPoint(0.f, 20, 30, cam, T_world_camera, image.data(), gradient.data(), {kW, kH}, T_rgb_world, cam,
                            gradient_sq)
                  .intensity,
              0.f);
    EXPECT_LT(gradient_sq, 0.f);
    EXPECT_LT(farFieldPoint(5.f, 0, 30, cam, T_world_camera, image.data(), gradient.data(), {kW, kH}, T_rgb_world, cam,
                            gradient_sq)
                  .intensity,
              0.f);
}

TEST(FarFieldPointTest, AFrameSeesAPointOnlyWhereItMeasuredNothingNearer) {
    const Intrinsics cam = smallCamera();
    const Mat4f T_world_camera = test::moveInCamera(Mat4f::identity(), {1.f, 0.f, 0.f}, 10.f, {0.5f, 0.f, 0.f});
    const Mat4f T_camera_world = rigidInverse(T_world_camera);
    std::vector<float> depth(kW * kH, 0.f);
    const ColorPoint point{transformPoint(T_world_camera, Vec3f{0.096f, 0.072f, 6.f}), 0.5f};  // on pixel (32.3, 24.2)
    EXPECT_EQ(unhiddenFarFieldPoint(point, depth.data(), {kW, kH}, T_camera_world, cam).intensity, 0.5f);
    depth[std::size_t(32 + 24 * kW)] = 1.f;  // a surface 1 m away in front of it
    EXPECT_LT(unhiddenFarFieldPoint(point, depth.data(), {kW, kH}, T_camera_world, cam).intensity, 0.f);

    depth.assign(depth.size(), 0.f);
    const ColorPoint behind{transformPoint(T_world_camera, Vec3f{0.f, 0.f, -6.f}), 0.5f};
    const ColorPoint outside{transformPoint(T_world_camera, Vec3f{6.f, 0.f, 6.f}), 0.5f};
    const ColorPoint uncoloured{point.p_world, -1.f};
    EXPECT_LT(unhiddenFarFieldPoint(behind, depth.data(), {kW, kH}, T_camera_world, cam).intensity, 0.f);
    EXPECT_LT(unhiddenFarFieldPoint(outside, depth.data(), {kW, kH}, T_camera_world, cam).intensity, 0.f);
    EXPECT_LT(unhiddenFarFieldPoint(uncoloured, depth.data(), {kW, kH}, T_camera_world, cam).intensity, 0.f);
    // Just in front of the camera's plane a point projects some 1e31 pixels out, beyond any int: unseen,
    // and judged without converting that coordinate (undefined behaviour, which UBSan reports).
    // (At the identity pose, so that the depth stays exactly 1e-30 m.)
    for (float side : {1.f, -1.f}) {
        const ColorPoint grazing{Vec3f{side, side, 1e-30f}, 0.5f};
        EXPECT_LT(unhiddenFarFieldPoint(grazing, depth.data(), {kW, kH}, Mat4f::identity(), cam).intensity, 0.f)
            << side;
    }
}

class FarFieldKeyframesTest : public ::testing::TestWithParam<Device> {
protected:
    void SetUp() override {
        VF_SKIP_IF_UNAVAILABLE(GetParam());
        kernels_ = makeColorTrackerKernels(GetParam());
        view_.calib.depth = smallCamera();
        view_.calib.rgb = smallCamera();
        // A far wall 5 m away everywhere; the colour image is plain on its left third and then grows
        // steeper to the right (a parabola in x): the steeper a pixel, the more its term constrains.
        view_.far_depth.resize({kW, kH});
        view_.depth.resize({kW, kH});
        view_.rgb.resize({kW, kH});
        for (int y = 0; y < kH; ++y)
            for (int x = 0; x < kW; ++x) {
                view_.far_depth.at(x, y) = 5.f;
                view_.depth.at(x, y) = 0.f;
                const auto v =
                    std::uint8_t(x < kPlainColumns ? 60 : 60 + 0.1f * float((x - kPlainColumns) * (x - kPlainColumns)));
                view_.rgb.at(x, y) = Vec4u8{v, v, v, 255};
            }
        kernels_->intensityFromRgb(view_.rgb, color_.intensity);
        kernels_->sobelGradient(color_.intensity, color_.gradient);
        color_.intrinsics = smallCamera();
    }

    std::unique_ptr<FarFieldKeyframes> keyframes(int keep, float point_share) {
        TrackerSettings s;
        s.far_field_keyframes = keep;
        s.far_field_point_share = point_share;
        return std::make_unique<FarFieldKeyframes>(*kernels_, s, GetParam());
    }

    // The points a frame at T_world_camera sees, on the host.
    std::vector<ColorPoint> seen(FarFieldKeyframes& far, const Mat4f& T_world_camera) {
        const Image<ColorPoint>* points = far.unhiddenPoints(view_, T_world_camera);
        if (!points) return {};
        std::vector<ColorPoint> all(points->pixelCount()), out;
        points->memory().readRange(points->memory().isCurrent(Device::CPU) ? Device::CPU : Device::CUDA, 0, all.data(),
                                   all.size());
        for (const ColorPoint& c : all)
            if (c.intensity >= 0.f) out.push_back(c);
        return out;
    }

    std::unique_ptr<ColorTrackerKernels> kernels_;
    View view_;
    ColorFrameLevel color_;
};

TEST_P(FarFieldKeyframesTest, KeepsTheLastKeyframesTakenEverySpacingOfMotion) {
    auto far = keyframes(3, 1.f);
    const Mat4f T0 = Mat4f::identity();
    EXPECT_EQ(far->unhiddenPoints(view_, T0), nullptr) << "no keyframe yet";
    far->offer(view_, T0, color_, Mat4f::identity());
    ASSERT_EQ(far->keyframeCount(), 1);
    const int per_keyframe = far->pointCount();
    // Every second pixel in x and y that has colour (a pixel from the sampling border): most of 32 x 24.
    EXPECT_GT(per_keyframe, 500);
    EXPECT_LE(per_keyframe, (kW / 2) * (kH / 2));

    far->offer(view_, test::moveInCamera(T0, {0.f, 1.f, 0.f}, 0.f, {0.03f, 0.f, 0.f}), color_, Mat4f::identity());
    EXPECT_EQ(far->keyframeCount(), 1) << "3 cm from the last keyframe: not yet";
    far->offer(view_, test::moveInCamera(T0, {0.f, 1.f, 0.f}, 0.f, {0.06f, 0.f, 0.f}), color_, Mat4f::identity());
    EXPECT_EQ(far->keyframeCount(), 2);
    far->offer(view_, test::moveInCamera(T0, {0.f, 1.f, 0.f}, 12.f, {0.06f, 0.f, 0.f}), color_, Mat4f::identity());
    EXPECT_EQ(far->keyframeCount(), 3) << "a 12 degree turn";
    far->offer(view_, test::moveInCamera(T0, {0.f, 1.f, 0.f}, 12.f, {0.12f, 0.f, 0.f}), color_, Mat4f::identity());
    EXPECT_EQ(far->keyframeCount(), 3) << "at most far_field_keyframes";
    // Pixels at the sampling border come and go with the rounding of each keyframe's pose.
    EXPECT_NEAR(double(far->pointCount()), 3.0 * per_keyframe, 0.05 * per_keyframe);

    far->forget();
    EXPECT_EQ(far->keyframeCount(), 0);
    EXPECT_EQ(far->unhiddenPoints(view_, T0), nullptr);

    view_.far_depth = Image<float>();
    far->offer(view_, T0, color_, Mat4f::identity());
    EXPECT_EQ(far->keyframeCount(), 0) << "a view without far depths adds nothing";
}

TEST_P(FarFieldKeyframesTest, AKeyframeKeepsItsBestTexturedPoints) {
    auto all = keyframes(1, 1.f), half = keyframes(1, 0.5f);
    all->offer(view_, Mat4f::identity(), color_, Mat4f::identity());
    half->offer(view_, Mat4f::identity(), color_, Mat4f::identity());
    EXPECT_NEAR(double(half->pointCount()), 0.5 * all->pointCount(), 0.1 * all->pointCount());
    // Two thirds of the points lie on the parabola, which is steeper the farther right: the plain
    // third is left out, and the kept points lie right of the candidates' middle (x = 31), give or
    // take the 8-bit rounding of the image.
    const std::vector<ColorPoint> kept = seen(*half, Mat4f::identity());
    ASSERT_EQ(int(kept.size()), half->pointCount());
    const Intrinsics cam = smallCamera();
    for (const ColorPoint& c : kept) EXPECT_GE(cam.project(c.p_world).x, 28.f);
}

TEST_P(FarFieldKeyframesTest, AFrameSeesThePointsNothingNearerHides) {
    auto far = keyframes(3, 1.f);
    far->offer(view_, Mat4f::identity(), color_, Mat4f::identity());
    const std::size_t all = seen(*far, Mat4f::identity()).size();
    ASSERT_EQ(int(all), far->pointCount());
    // A near object covers the frame's top half: the points behind it drop out.
    for (int y = 0; y < kH / 2; ++y)
        for (int x = 0; x < kW; ++x) view_.depth.at(x, y) = 1.f;
    const std::vector<ColorPoint> unhidden = seen(*far, Mat4f::identity());
    EXPECT_NEAR(double(unhidden.size()), 0.5 * double(all), 0.1 * double(all));
    for (const ColorPoint& c : unhidden) EXPECT_GE(smallCamera().project(c.p_world).y, kH / 2 - 0.5f);
    // A frame turned 20 degrees sees only part of the wall.
    view_.depth.memory().fillBytes(0);
    const std::size_t turned =
        seen(*far, test::moveInCamera(Mat4f::identity(), {0.f, 1.f, 0.f}, 20.f, {0.f, 0.f, 0.f})).size();
    EXPECT_GT(turned, 0u);
    EXPECT_LT(turned, all);
}

INSTANTIATE_TEST_SUITE_P(Devices, FarFieldKeyframesTest, test::kAllDevices, test::DeviceName());

}  // namespace
}  // namespace voxfuse
