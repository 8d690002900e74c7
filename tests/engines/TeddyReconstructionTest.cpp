// Real recorded frames: with ground-truth poses on TUM fr3/teddy, the model raycast at frame 100
// must reproduce that frame's measured depth (median absolute error under 1 cm).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/io/ImageSource.h"

namespace voxfuse {
namespace {

TEST(TeddyReconstructionTest, RaycastAtFrame100MatchesMeasuredDepth) {
    const std::string dir = std::string(VOXFUSE_SHARED_DATA_DIR) + "/tum_fr3_teddy_200";
    if (!std::filesystem::exists(dir + "/rgb.txt"))
        GTEST_SKIP() << "../shared/data not found at " << dir << ": skipping the teddy test";

    auto source = openImageSource(dir);
    MainEngineSettings s;  // 5 mm voxels, mu 2 cm, the voxel block hash: the defaults
    s.voxel_type = VoxelType::S;
    auto engine = MainEngine::create(s, source->calib());

    RGBDFrame frame;
    bool have_origin = false;
    Mat4f T_origin_world = Mat4f::identity();
    int fused = 0;
    while (source->next(frame) && frame.index <= 100) {
        if (!frame.has_ground_truth) continue;
        if (!have_origin) {
            T_origin_world = rigidInverse(frame.T_world_camera_gt);
            have_origin = true;
        }
        const Mat4f pose = T_origin_world * frame.T_world_camera_gt;
        engine->processFrame(frame, &pose);
        ++fused;
    }
    ASSERT_EQ(frame.index, 101) << "the loop stops after frame 100";
    EXPECT_GE(fused, 90);

    Image<float> raycast;
    raycastDepth(engine->renderState(), raycast);
    const Image<float>& measured = engine->view().depth;
    ASSERT_EQ(engine->view().frame_index, 100);
    std::vector<float> errors;
    for (std::size_t i = 0; i < raycast.pixelCount(); ++i)
        if (raycast.host()[i] > 0.f && measured.host()[i] > 0.f)
            errors.push_back(std::fabs(raycast.host()[i] - measured.host()[i]));
    // Parts of the frame beyond the 3 m depth limit, or never seen before, are not in the model.
    std::size_t measured_valid = 0;
    for (std::size_t i = 0; i < measured.pixelCount(); ++i) measured_valid += measured.host()[i] > 0.f;
    ASSERT_GT(errors.size(), measured.pixelCount() / 4) << "the model should explain a good part of the frame";
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    const float median_m = errors[errors.size() / 2];
    std::printf(
        "[ teddy    ] frames fused %d, raycast-vs-measured median |error| at frame 100: %.2f mm over %zu pixels "
        "(%zu measured)\n",
        fused, 1000.f * median_m, errors.size(), measured_valid);
    EXPECT_LT(median_m, 0.01f);
}

}  // namespace
}  // namespace voxfuse
