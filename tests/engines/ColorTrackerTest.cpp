// The colour tracker on exact synthetic frames of the textured room: a small known motion must be
// recovered from the photometric error alone; frames without colour fail cleanly.

#include <gtest/gtest.h>

#include "DeviceTestSupport.h"
#include "TrackingTestSupport.h"
#include "engines/PhotometricFrames.h"
#include "voxfuse/engines/Tracker.h"
#include "voxfuse/shared/ColorTrackerTerms.h"

namespace voxfuse {
namespace {

const synth::SyntheticScene& room() {
    static const synth::SyntheticScene scene = synth::SyntheticScene::defaultRoom();
    return scene;
}
Mat4f startPose() { return test::lookAt({-1.6f, -1.3f, 1.5f}, {0.15f, 0.1f, 0.75f}); }

TrackerSettings colorSettings() {
    TrackerSettings s;
    s.kind = TrackerKind::Color;
    return s;
}

class ColorTrackerTest : public ::testing::TestWithParam<Device> {
protected:
    void SetUp() override { VF_SKIP_IF_UNAVAILABLE(GetParam()); }
};

TEST_P(ColorTrackerTest, RecoversASmallMotion) {
    const Intrinsics intr = test::kinectIntrinsics();
    const View first = test::renderView(room(), intr, startPose());
    const Mat4f moved = test::moveInCamera(startPose(), {0.4f, 1.f, 0.1f}, 1.5f, {0.015f, -0.01f, 0.01f});
    auto tracker = makeTracker(colorSettings(), GetParam());
    TrackingState state;
    state.T_world_camera = startPose();
    tracker->track(state, first, test::emptyModel(intr));  // remembers the colour of the model's frame
    ASSERT_EQ(state.quality, TrackingQuality::Good);

    tracker->track(state, test::renderView(room(), intr, moved), test::modelFromView(first, startPose()));
    EXPECT_EQ(state.quality, TrackingQuality::Good);
    EXPECT_LT(test::translationErrorM(state.T_world_camera, moved), 0.003f);
    EXPECT_LT(test::rotationErrorDeg(state.T_world_camera, moved), 0.1f);
    EXPECT_GT(state.inlier_ratio, 0.8f);
    EXPECT_LT(state.residual_m, 0.03f) << "RMS intensity error (aliased texture edges and occlusions)";
    EXPECT_GT(tracker->lastStats().levels.back().iterations, 0);
}

TEST_P(ColorTrackerTest, AColorImageOfAnotherSizeIsTheCalibratedCameraAtThatResolution) {
    // Colour at twice the depth's resolution, the calibration at the depth's (as integration takes it):
    // the colour camera's intrinsics scale with the image, and the motion is recovered all the same.
    const Intrinsics intr = test::kinectIntrinsics();
    const Intrinsics large = test::kinectIntrinsics(1280, 960);
    const auto withLargeColor = [&](const Mat4f& T_world_camera) {
        View view = test::renderView(room(), intr, T_world_camera);
        view.rgb = test::renderView(room(), large, T_world_camera).rgb;
        return view;
    };
    const View first = withLargeColor(startPose());
    const Mat4f moved = test::moveInCamera(startPose(), {0.4f, 1.f, 0.1f}, 1.5f, {0.015f, -0.01f, 0.01f});
    auto tracker = makeTracker(colorSettings(), GetParam());
    TrackingState state;
    state.T_world_camera = startPose();
    tracker->track(state, first, test::emptyModel(intr));
    tracker->track(state, withLargeColor(moved), test::modelFromView(first, startPose()));
    EXPECT_EQ(state.quality, TrackingQuality::Good);
    EXPECT_LT(test::translationErrorM(state.T_world_camera, moved), 0.003f);
    EXPECT_LT(test::rotationErrorDeg(state.T_world_camera, moved), 0.1f);
}

TEST_P(ColorTrackerTest, AMotionBeyondItsBasinIsReportedFailed) {
    // Photometric alignment only converges within a few pixels: 8 cm and 8 degrees is far beyond.
    const Intrinsics intr = test::kinectIntrinsics();
    const View first = test::renderView(room(), intr, startPose());
    const Mat4f moved = test::moveInCamera(startPose(), {0.3f, 1.f, -0.2f}, 8.f, {0.06f, 0.03f, -0.045f});
    auto tracker = makeTracker(colorSettings(), GetParam());
    TrackingState state;
    state.T_world_camera = startPose();
    tracker->track(state, first, test::emptyModel(intr));
    tracker->track(state, test::renderView(room(), intr, moved), test::modelFromView(first, startPose()));
    EXPECT_EQ(state.quality, TrackingQuality::Failed);
    EXPECT_GT(state.residual_m, colorSettings().failed_color_residual);
    EXPECT_EQ(test::translationErrorM(state.T_world_camera, startPose()), 0.f);
}

TEST_P(ColorTrackerTest, ViewWithoutColorFailsAndKeepsThePose) {
    const Intrinsics intr = test::kinectIntrinsics(320, 240);
    const View first = test::renderView(room(), intr, startPose());
    auto tracker = makeTracker(colorSettings(), GetParam());
    TrackingState state;
    state.T_world_camera = startPose();
    tracker->track(state, first, test::emptyModel(intr));
    const View grey = test::renderView(room(), intr, startPose(), false);
    tracker->track(state, grey, test::modelFromView(first, startPose()));
    EXPECT_EQ(state.quality, TrackingQuality::Failed);
    EXPECT_EQ(test::translationErrorM(state.T_world_camera, startPose()), 0.f);
}

TEST_P(ColorTrackerTest, WithoutAnEarlierColorFrameThePoseIsKeptAsPoor) {
    const Intrinsics intr = test::kinectIntrinsics(320, 240);
    const View first = test::renderView(room(), intr, startPose());
    auto tracker = makeTracker(colorSettings(), GetParam());
    TrackingState state;
    state.T_world_camera = startPose();
    tracker->track(state, first, test::modelFromView(first, startPose()));
    EXPECT_EQ(state.quality, TrackingQuality::Poor);
}

// A model that carries the map's colours (RenderState::intensity: what MainEngine gives the rgbd
// tracker) is aligned to them: no earlier frame is needed, as after a reset or a relocalisation.
TEST_P(ColorTrackerTest, AModelCarryingTheMapsColorsNeedsNoEarlierFrame) {
    const Intrinsics intr = test::kinectIntrinsics();
    const View first = test::renderView(room(), intr, startPose());
    const Mat4f moved = test::moveInCamera(startPose(), {0.4f, 1.f, 0.1f}, 1.5f, {0.015f, -0.01f, 0.01f});
    RenderState model = test::modelFromView(first, startPose());
    TrackingState state;
    state.T_world_camera = startPose();
    makeTracker(colorSettings(), GetParam())->track(state, test::renderView(room(), intr, moved), model);
    EXPECT_NE(state.quality, TrackingQuality::Good) << "no earlier frame and no map colours: nothing to align to";
    EXPECT_EQ(test::translationErrorM(state.T_world_camera, startPose()), 0.f);

    model.intensity.resize(intr.size());
    for (std::size_t i = 0; i < model.intensity.pixelCount(); ++i)
        model.intensity.host()[i] = intensityFromRgb(first.rgb.host()[i]);
    state.T_world_camera = startPose();
    makeTracker(colorSettings(), GetParam())->track(state, test::renderView(room(), intr, moved), model);
    EXPECT_EQ(state.quality, TrackingQuality::Good);
    EXPECT_LT(test::translationErrorM(state.T_world_camera, moved), 0.003f);
    EXPECT_LT(test::rotationErrorDeg(state.T_world_camera, moved), 0.1f);
}

// The previous frame colours the model only while the map does not: once the map has, the frame is
// not kept (it would be read by no later model), and a model without colours then finds nothing.
TEST_P(ColorTrackerTest, ThePreviousFrameIsKeptOnlyWhileTheMapGivesNoColors) {
    const Intrinsics intr = test::kinectIntrinsics(320, 240);
    const View view = test::renderView(room(), intr, startPose());
    const RenderState plain = test::modelFromView(view, startPose());
    RenderState colored = test::modelFromView(view, startPose());
    colored.intensity.resize(intr.size());
    for (std::size_t i = 0; i < colored.intensity.pixelCount(); ++i)
        colored.intensity.host()[i] = intensityFromRgb(view.rgb.host()[i]);
    auto kernels = makeColorTrackerKernels(GetParam());
    PhotometricFrames frames(*kernels);
    const auto nextFrame = [&](const RenderState& model) {
        EXPECT_TRUE(frames.prepare(view, 3));
        const bool colored_model = frames.colorModel(model, 2);
        frames.rememberCurrent(startPose());
        return colored_model;
    };
    EXPECT_FALSE(nextFrame(plain)) << "no earlier frame, no map colours";
    EXPECT_TRUE(frames.holdsPreviousFrame());
    EXPECT_TRUE(nextFrame(plain));  // from the previous frame
    EXPECT_TRUE(frames.holdsPreviousFrame());
    EXPECT_TRUE(nextFrame(colored));
    EXPECT_FALSE(frames.holdsPreviousFrame());
    EXPECT_FALSE(nextFrame(plain));
    EXPECT_TRUE(frames.holdsPreviousFrame());
}

INSTANTIATE_TEST_SUITE_P(Devices, ColorTrackerTest, test::kAllDevices, test::DeviceName());

TEST(ColorTrackerTermsTest, JacobianMatchesFiniteDifferences) {
    // A smooth synthetic image I(x, y) = 0.5 + 0.3 sin(0.05 x) cos(0.07 y) seen by a camera offset from the depth
    // camera.
    const Intrinsics rgb{200, 150, 180.f, 180.f, 99.5f, 74.5f};
    std::vector<float> image(200 * 150);
    std::vector<Vec2f> gradient(200 * 150);
    for (int y = 0; y < 150; ++y)
        for (int x = 0; x < 200; ++x)
            image[std::size_t(x + y * 200)] = 0.5f + 0.3f * std::sin(0.05f * x) * std::cos(0.07f * y);
    for (int y = 0; y < 150; ++y)
        for (int x = 0; x < 200; ++x)
            gradient[std::size_t(x + y * 200)] = sobelGradientPixel(image.data(), {200, 150}, x, y);
    const Mat4f T_world_camera = test::moveInCamera(Mat4f::identity(), {1.f, 2.f, 3.f}, 5.f, {0.1f, -0.05f, 0.2f});
    const Mat4f T_rgb_depth = test::moveInCamera(Mat4f::identity(), {0.f, 1.f, 0.f}, 2.f, {-0.025f, 0.f, 0.f});
    const ColorPoint point{transformPoint(T_world_camera, Vec3f{0.1f, 0.05f, 1.2f}), 0.4f};

    auto residualAt = [&](const Mat4f& pose, float J[6]) {
        float r = 0.f;
        const ColorTermParams params{rigidInverse(pose), T_rgb_depth, rgb};
        EXPECT_TRUE(photometricTerm(point, image.data(), gradient.data(), {200, 150}, params, J, r));
        return r;
    };
    float J[6], unused[6];
    residualAt(T_world_camera, J);
    const float h = 1e-3f;
    for (int k = 0; k < 6; ++k) {
        Eigen::Matrix<float, 6, 1> x = Eigen::Matrix<float, 6, 1>::Zero();
        x(k) = h;
        // A first-order step is enough for a central difference: T * (I + [x]) up to O(h^2).
        auto stepped = [&](float sign) {
            const Eigen::Vector3f w = sign * x.head<3>(), v = sign * x.tail<3>();
            return test::moveInCamera(T_world_camera, w.norm() > 0.f ? w : Eigen::Vector3f::UnitX(),
                                      w.norm() * 180.f / float(EIGEN_PI), v);
        };
        const float numeric = (residualAt(stepped(1.f), unused) - residualAt(stepped(-1.f), unused)) / (2.f * h);
        EXPECT_NEAR(J[k], numeric, 0.02f * std::fabs(numeric) + 2e-3f) << "parameter " << k;
    }
}

}  // namespace
}  // namespace voxfuse
