// The whole per-frame pipeline on synthetic frames with exact poses, for every voxel type and device.

#include <gtest/gtest.h>

#include <cmath>
#include <tuple>

#include "DeviceTestSupport.h"
#include "SyntheticViews.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/engines/MainEngine.h"

namespace voxfuse {
namespace {

class MainEngineVoxelTest : public ::testing::TestWithParam<std::tuple<Device, VoxelType>> {
protected:
    void SetUp() override { VF_SKIP_IF_UNAVAILABLE(std::get<0>(GetParam())); }
};

TEST_P(MainEngineVoxelTest, RaycastReproducesTheLastFrameDepth) {
    MainEngineSettings s;
    s.device = std::get<0>(GetParam());
    s.voxel_type = std::get<1>(GetParam());
    s.scene.voxel_size_m = 0.01f;
    s.scene.mu_m = 0.04f;
    s.dense_offset = {-80, -80, -10};
    s.dense_size = {160, 160, 100};
    const Intrinsics intr = test::kinectIntrinsics(160, 120);
    RGBDCalib calib;
    calib.depth = calib.rgb = intr;
    calib.disparity = DisparityCalib::affine(0.001f);
    auto engine = MainEngine::create(s, calib);

    const synth::SyntheticScene world = synth::SyntheticScene::boxAndSphere();
    Mat4f pose;
    View last;
    for (int k = 0; k < 5; ++k) {
        pose = test::lookAt({1.0f + 0.05f * k, -0.8f + 0.1f * k, 0.7f}, {0.3f, 0.f, 0.1f});
        last = test::renderView(world, intr, pose);
        const FrameResult r = engine->processFrame(test::toRgbdFrame(last, k), &pose);
        EXPECT_TRUE(r.fused);
        ASSERT_EQ(r.stages.size(), 5u);
        EXPECT_GT(r.total_ms, 0.0);
    }
    Image<float> depth;
    raycastDepth(engine->renderState(), depth);
    std::vector<float> errors;
    for (std::size_t i = 0; i < depth.pixelCount(); ++i)
        if (depth.host()[i] > 0.f && last.depth.host()[i] > 0.f) errors.push_back(std::fabs(depth.host()[i] - last.depth.host()[i]));
    ASSERT_GT(errors.size(), 0.5 * depth.pixelCount()) << "the floor beyond the small volume is not in the model";
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    EXPECT_LT(errors[errors.size() / 2], 0.003f) << "median raycast depth error (mm depth quantisation, 1 cm voxels)";

    Image<Vec4u8> image;
    engine->renderLast(RenderMode::Color, image);
    EXPECT_EQ(image.size(), intr.size());
    engine->renderFromPose(test::lookAt({-0.5f, -1.0f, 1.0f}, {0.3f, 0.f, 0.1f}), intr, RenderMode::Shaded, image);
    int lit = 0;
    for (std::size_t i = 0; i < image.pixelCount(); ++i) lit += image.host()[i].x > 0;
    EXPECT_GT(lit, int(image.pixelCount() / 4)) << "a free viewpoint sees the fused surfaces";
}

INSTANTIATE_TEST_SUITE_P(AllVoxelTypes, MainEngineVoxelTest,
                         ::testing::Combine(test::kAllDevices, ::testing::Values(VoxelType::S, VoxelType::F, VoxelType::SRgb, VoxelType::FRgb,
                                                                                 VoxelType::SLabel, VoxelType::SRgbLabel)),
                         [](const auto& info) {
                             return std::string(deviceName(std::get<0>(info.param))) + "_" + toString(std::get<1>(info.param));
                         });

TEST(MainEngineTest, RejectsBadSettingsWithClearErrors) {
    RGBDCalib calib;
    calib.depth = calib.rgb = test::kinectIntrinsics(160, 120);
    MainEngineSettings s;
    s.dense_size = {16, 16, 16};
    s.scene.mu_m = s.scene.voxel_size_m / 2;
    EXPECT_THROW(MainEngine::create(s, calib), ConfigError);
    s.scene.mu_m = 0.02f;
    EXPECT_THROW(MainEngine::create(s, RGBDCalib{}), ConfigError);
    EXPECT_THROW(parseVoxelType("double"), ConfigError);
    auto engine = MainEngine::create(s, calib);
    RGBDFrame frame;
    frame.depth_raw.resize({10, 10});
    const Mat4f pose = Mat4f::identity();
    EXPECT_THROW(engine->processFrame(frame, &pose), IoError) << "depth size disagrees with the calibration";
}

}  // namespace
}  // namespace voxfuse
