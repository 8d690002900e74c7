// The pipeline with its scene on the GPU (--device cuda: allocation, integration and raycast in CUDA,
// tracking on the CPU from the raycast brought back) against the same pipeline on the CPU, on
// synthetic frames. Tracked independently, the poses may differ by the GPU's rounding of the sums the
// tracker reads (a tolerance, said where it is used); at the same poses, the blocks, the mesh and the
// renders are the same bit for bit. Skips visibly without a GPU.

#include <gtest/gtest.h>

#include <cmath>
#include <utility>

#include "DeviceTestSupport.h"
#include "SyntheticViews.h"
#include "voxfuse/engines/MainEngine.h"

namespace voxfuse {
namespace {

class MainEngineCudaTest : public ::testing::TestWithParam<IndexType> {
protected:
    void SetUp() override { VF_SKIP_IF_UNAVAILABLE(Device::CUDA); }
};

TEST_P(MainEngineCudaTest, TrackedRunMatchesTheCpuPipeline) {
    MainEngineSettings s;
    s.voxel_type = VoxelType::SRgb;
    s.index_type = GetParam();
    s.scene.voxel_size_m = 0.01f;
    s.scene.mu_m = 0.04f;
    // The world is the first camera's frame: the dense array spans what that camera sees up to 2 m
    // (x -1.3..1.3, y -1..0.5, depth 0.7..2.1 m). An array that cut the view at 1 m depth left a
    // third of each frame's pixels with a model to meet, and a tracking problem so poorly conditioned
    // (condition 2e-4) that a 10 um change of the input moved the pose by 0.6 mm: there the GPU's
    // rounding alone set the devices 1.4 mm apart. Here 10 um moves it by 20 um at most.
    s.scene.view_frustum_max_m = 2.0f;
    s.dense_offset = {-130, -100, 70};
    s.dense_size = {260, 150, 140};
    const Intrinsics intr = test::kinectIntrinsics(320, 240);
    RGBDCalib calib;
    calib.depth = calib.rgb = intr;
    calib.disparity = DisparityCalib::affine(0.001f);
    auto on_cpu = MainEngine::create(s, calib);
    s.device = Device::CUDA;
    auto on_gpu = MainEngine::create(s, calib);

    const synth::SyntheticScene world = synth::SyntheticScene::boxAndSphere();
    for (int k = 0; k < 12; ++k) {
        const Mat4f pose = test::lookAt({1.0f + 0.01f * k, -0.8f + 0.02f * k, 0.7f}, {0.3f, 0.f, 0.1f});
        const RGBDFrame frame = test::toRgbdFrame(test::renderView(world, intr, pose), k);
        const FrameResult a = on_cpu->processFrame(frame, nullptr), b = on_gpu->processFrame(frame, nullptr);
        ASSERT_EQ(a.fused, b.fused) << "frame " << k;
        EXPECT_EQ(a.quality, TrackingQuality::Good) << "frame " << k << ": a well-posed comparison";
        EXPECT_EQ(a.allocation.blocks_allocated, b.allocation.blocks_allocated) << "frame " << k;
        const Vec3f dt = a.T_world_camera.translation() - b.T_world_camera.translation();
        EXPECT_LT(length(dt), 1e-3f) << "frame " << k << ": poses within 1 mm";
    }
    Mesh mc, mg;
    on_cpu->extractMesh(mc);
    on_gpu->extractMesh(mg);
    EXPECT_GT(mc.triangles.size(), 1000u);
    // Independently tracked poses differ (within 1 mm, above): so may the surfaces, slightly.
    EXPECT_NEAR(double(mg.triangles.size()), double(mc.triangles.size()), 0.005 * double(mc.triangles.size()));

    // The GPU pipeline at the CPU's tracked poses: the same arithmetic on the same inputs, so the same
    // blocks every frame and the same mesh and render, bit for bit.
    s.device = Device::CPU;
    auto tracked = MainEngine::create(s, calib);
    s.device = Device::CUDA;
    auto given = MainEngine::create(s, calib);
    for (int k = 0; k < 12; ++k) {
        const Mat4f pose = test::lookAt({1.0f + 0.01f * k, -0.8f + 0.02f * k, 0.7f}, {0.3f, 0.f, 0.1f});
        const RGBDFrame frame = test::toRgbdFrame(test::renderView(world, intr, pose), k);
        const FrameResult a = tracked->processFrame(frame, nullptr);
        const FrameResult b = given->processFrame(frame, &a.T_world_camera);
        ASSERT_EQ(a.fused, b.fused) << "frame " << k;
        EXPECT_EQ(a.allocation.blocks_allocated, b.allocation.blocks_allocated) << "frame " << k;
        EXPECT_EQ(a.allocation.visible_blocks, b.allocation.visible_blocks) << "frame " << k;
    }
    Mesh ma, mb;
    tracked->extractMesh(ma);
    given->extractMesh(mb);
    ASSERT_GT(ma.triangles.size(), 1000u);
    test::ChannelDifferences d;
    ASSERT_EQ(ma.vertices.size(), mb.vertices.size());
    ASSERT_EQ(ma.triangles.size(), mb.triangles.size());
    test::addImageDifferences<Vec3f, 3>(d, "vertex", ma.vertices.data(), mb.vertices.data(), ma.vertices.size());
    test::addImageDifferences<Vec3f, 3>(d, "normal", ma.normals.data(), mb.normals.data(), ma.normals.size());
    test::addImageDifferences<Vec3i, 3>(d, "triangle", ma.triangles.data(), mb.triangles.data(), ma.triangles.size());
    ASSERT_EQ(ma.colors.size(), mb.colors.size());
    test::addImageDifferences<Vec3u8, 3>(d, "colour", ma.colors.data(), mb.colors.data(), ma.colors.size());
    EXPECT_TRUE(d.none()) << "mesh at the same poses: " << d.describe();
    Image<Vec4u8> ia, ib;
    tracked->renderLast(RenderMode::Color, ia);
    given->renderLast(RenderMode::Color, ib);
    ib.memory().updateHost();
    test::ChannelDifferences r;
    test::addImageDifferences<Vec4u8, 4>(r, "rgba", std::as_const(ia), std::as_const(ib));
    EXPECT_TRUE(r.none()) << "render at the same pose: " << r.describe();
}

// The automatic block ceiling on the GPU asks the device for its free memory: a small table gets a
// block for every entry, the default table more than DESIGN.md's 2^18 on a GPU with room for them.
TEST(MainEngineCudaCeiling, FollowsTheTableAndTheGpusFreeMemory) {
    VF_SKIP_IF_UNAVAILABLE(Device::CUDA);
    RGBDCalib calib;
    calib.depth = calib.rgb = test::kinectIntrinsics(64, 48);
    calib.disparity = DisparityCalib::affine(0.001f);
    MainEngineSettings s;
    s.device = Device::CUDA;
    s.hash.bucket_count = 4096;
    s.hash.excess_entry_count = 1024;
    EXPECT_EQ(MainEngine::create(s, calib)->settings().hash.max_block_count, 5120);
    s.hash = MainEngineSettings{}.hash;
    const double free_bytes = double(device_memory::freeDeviceBytes());
    ASSERT_GT(free_bytes, 0.0);
    const int chosen = MainEngine::create(s, calib)->settings().hash.max_block_count;
    // Within a step of 2^16 blocks: the free memory may move between the two queries.
    EXPECT_NEAR(chosen, automaticMaxBlockCount(Device::CUDA, sizeof(VoxelSRgb), s.hash, free_bytes), 1 << 16)
        << "free memory " << free_bytes / double(1 << 20) << " MiB";
    if (free_bytes > 8.0 * double(1ull << 30)) {
        EXPECT_GT(chosen, 1 << 18);
    }
}

INSTANTIATE_TEST_SUITE_P(Indexes, MainEngineCudaTest, ::testing::Values(IndexType::Hash, IndexType::Dense),
                         [](const auto& info) { return std::string(toString(info.param)); });

}  // namespace
}  // namespace voxfuse
