// The scene engines on the GPU against their CPU layer, for every voxel type and both indexes, frame
// by frame on the same synthetic views (with colour and classes), at the same poses. Both devices run
// the same loop bodies, built without fused multiply-adds (src/CMakeLists.txt), so everything must
// agree bit for bit: the hash's table entry for entry, every channel of every voxel, every channel of
// every raycast pixel (points, normals, depth ranges) and of every render mode. A difference is
// reported as counts per channel (DeviceTestSupport.h). Skips visibly without a GPU.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <utility>

#include "DeviceTestSupport.h"
#include "SyntheticViews.h"
#include "voxfuse/engines/AllocationEngine.h"
#include "voxfuse/engines/IntegrationEngine.h"
#include "voxfuse/engines/RaycastEngine.h"
#include "voxfuse/objects/Voxel.h"

namespace voxfuse {
namespace {

template <class TVoxel>
class EngineCudaParityTest : public ::testing::Test {
protected:
    void SetUp() override { VF_SKIP_IF_UNAVAILABLE(Device::CUDA); }
};
using VoxelTypes = ::testing::Types<VoxelS, VoxelF, VoxelSRgb, VoxelFRgb, VoxelSLabel, VoxelSRgbLabel>;
TYPED_TEST_SUITE(EngineCudaParityTest, VoxelTypes);

std::vector<Mat4f> cameraPath() {
    std::vector<Mat4f> poses;
    for (int k = 0; k < 6; ++k)
        poses.push_back(test::lookAt({1.0f - 0.15f * k, -0.8f + 0.3f * k, 0.8f - 0.04f * k}, {0.2f, 0.f, 0.1f}));
    return poses;
}

View frameView(const Mat4f& pose, int k) {
    static const synth::SyntheticScene world = synth::SyntheticScene::boxAndSphere();
    return test::labelledView(world, test::kinectIntrinsics(320, 240), pose, k);
}

// Every channel of every voxel, bit for bit; and the map is not empty.
template <class TVoxel>
void expectSameVoxels(const MemoryBlock<TVoxel>& cpu, const MemoryBlock<TVoxel>& gpu) {
    long long observed = 0, labelled = 0;
    for (std::size_t i = 0; i < cpu.size(); ++i) {
        observed += cpu.host()[i].w_depth > 0;
        if constexpr (TVoxel::hasLabel) labelled += cpu.host()[i].w_label > 0;
    }
    EXPECT_GT(observed, 50000);
    if constexpr (TVoxel::hasLabel) {
        EXPECT_GT(labelled, 5000) << "the label path ran";
    }
    const test::ChannelDifferences d = test::voxelDifferences(cpu, gpu);
    EXPECT_TRUE(d.none()) << "voxels: " << d.describe();
}

// Every channel of every raycast pixel, bit for bit. The GPU's results are read through a const view:
// a writable host() would mark the device copy stale, and render() then refuses it.
void expectSameRaycast(const RenderState& cpu, RenderState& gpu_raycast) {
    gpu_raycast.updateHost();
    gpu_raycast.depth_range.memory().updateHost();
    const RenderState& gpu = gpu_raycast;
    long long hits = 0;
    for (std::size_t i = 0; i < cpu.points_world.pixelCount(); ++i) hits += cpu.points_world.host()[i].w > 0.f;
    EXPECT_GT(hits, 20000);
    const test::ChannelDifferences d = test::raycastDifferences(cpu, gpu);
    EXPECT_TRUE(d.none()) << "raycast: " << d.describe();
}

// Every render mode, every channel of every pixel.
template <class TVoxel, class TIndex>
void expectSameRenders(RaycastEngine<TVoxel, TIndex>& cpu_engine, const Scene<TVoxel, TIndex>& on_cpu,
                       const RenderState& rc, RaycastEngine<TVoxel, TIndex>& gpu_engine,
                       const Scene<TVoxel, TIndex>& on_gpu, const RenderState& rg) {
    for (RenderMode mode :
         {RenderMode::Shaded, RenderMode::Color, RenderMode::Normals, RenderMode::Depth, RenderMode::Class}) {
        Image<Vec4u8> ic, ig;
        cpu_engine.render(on_cpu, rc, mode, ic);
        gpu_engine.render(on_gpu, rg, mode, ig);
        ig.memory().updateHost();
        test::ChannelDifferences d;
        test::addImageDifferences<Vec4u8, 4>(d, "rgba", std::as_const(ic), std::as_const(ig));
        EXPECT_TRUE(d.none()) << "render mode " << int(mode) << ": " << d.describe();
    }
}

TYPED_TEST(EngineCudaParityTest, HashAllocatesTheSameTableAndFusesAndRaycastsTheSameModel) {
    using TVoxel = TypeParam;
    const SceneParams params = test::centimetreSceneParams();
    Scene<TVoxel, VoxelBlockHash> on_cpu(params, VoxelBlockHash(VoxelBlockHashSettings(), Device::CPU), Device::CPU);
    Scene<TVoxel, VoxelBlockHash> on_gpu(params, VoxelBlockHash(VoxelBlockHashSettings(), Device::CUDA), Device::CUDA);
    auto cpu_allocation = makeAllocationEngine<TVoxel, VoxelBlockHash>(Device::CPU);
    auto gpu_allocation = makeAllocationEngine<TVoxel, VoxelBlockHash>(Device::CUDA);
    auto cpu_integration = makeIntegrationEngine<TVoxel, VoxelBlockHash>(Device::CPU);
    auto gpu_integration = makeIntegrationEngine<TVoxel, VoxelBlockHash>(Device::CUDA);
    auto cpu_raycast = makeRaycastEngine<TVoxel, VoxelBlockHash>(Device::CPU);
    auto gpu_raycast = makeRaycastEngine<TVoxel, VoxelBlockHash>(Device::CUDA);
    int k = 0;
    for (const Mat4f& pose : cameraPath()) {
        const View view = frameView(pose, k++);
        const AllocationStats a = cpu_allocation->allocate(on_cpu, view, pose);
        const AllocationStats b = gpu_allocation->allocate(on_gpu, view, pose);
        EXPECT_EQ(a.blocks_allocated, b.blocks_allocated);
        EXPECT_EQ(a.visible_blocks, b.visible_blocks);
        EXPECT_EQ(a.allocation_failures_total, b.allocation_failures_total);
        cpu_integration->integrate(on_cpu, view, pose);
        gpu_integration->integrate(on_gpu, view, pose);
        RenderState rc, rg;
        cpu_raycast->raycast(on_cpu, view.calib.depth, pose, rc);
        gpu_raycast->raycast(on_gpu, view.calib.depth, pose, rg);
        expectSameRaycast(rc, rg);
        if (k == 3) {
            EXPECT_EQ(cpu_allocation->removeEmptyBlocks(on_cpu), gpu_allocation->removeEmptyBlocks(on_gpu));
        }
    }
    const Scene<TVoxel, VoxelBlockHash> gpu_copy = test::onHost(on_gpu);
    const VoxelBlockHash &hc = on_cpu.index(), &hg = gpu_copy.index();
    ASSERT_EQ(hc.blocksInUse(), hg.blocksInUse());
    ASSERT_EQ(test::firstDifferentEntry(hc, hg), -1) << "the same table, entry for entry";
    ASSERT_EQ(hc.visibleCount(), hg.visibleCount());
    ASSERT_EQ(0, std::memcmp(hc.visibleEntries(), hg.visibleEntries(), std::size_t(hc.visibleCount()) * sizeof(int)));
    // The same blocks at the same places: the voxel arrays compare element by element.
    expectSameVoxels(on_cpu.voxels(), gpu_copy.voxels());

    // A free viewpoint (depth ranges from every allocated block) and the renders.
    const Mat4f free_view = test::lookAt({0.2f, 1.1f, 0.9f}, {0.2f, 0.f, 0.1f});
    RenderState rc, rg;
    cpu_raycast->raycast(on_cpu, test::kinectIntrinsics(320, 240), free_view, rc);
    gpu_raycast->raycast(on_gpu, test::kinectIntrinsics(320, 240), free_view, rg);
    expectSameRaycast(rc, rg);
    expectSameRenders(*cpu_raycast, on_cpu, rc, *gpu_raycast, on_gpu, rg);
}

TYPED_TEST(EngineCudaParityTest, DenseFusesAndRaycastsTheSameModel) {
    using TVoxel = TypeParam;
    const SceneParams params = test::centimetreSceneParams();
    const PlainVoxelArray index({-80, -80, -20}, {180, 160, 100});
    Scene<TVoxel, PlainVoxelArray> on_cpu(params, index, Device::CPU), on_gpu(params, index, Device::CUDA);
    auto cpu_integration = makeIntegrationEngine<TVoxel, PlainVoxelArray>(Device::CPU);
    auto gpu_integration = makeIntegrationEngine<TVoxel, PlainVoxelArray>(Device::CUDA);
    auto cpu_raycast = makeRaycastEngine<TVoxel, PlainVoxelArray>(Device::CPU);
    auto gpu_raycast = makeRaycastEngine<TVoxel, PlainVoxelArray>(Device::CUDA);
    int k = 0;
    for (const Mat4f& pose : cameraPath()) {
        const View view = frameView(pose, k++);
        cpu_integration->integrate(on_cpu, view, pose);
        gpu_integration->integrate(on_gpu, view, pose);
        RenderState rc, rg;
        cpu_raycast->raycast(on_cpu, view.calib.depth, pose, rc);
        gpu_raycast->raycast(on_gpu, view.calib.depth, pose, rg);
        expectSameRaycast(rc, rg);
        if (k == 6) expectSameRenders(*cpu_raycast, on_cpu, rc, *gpu_raycast, on_gpu, rg);
    }
    const Scene<TVoxel, PlainVoxelArray> gpu_copy = test::onHost(on_gpu);
    expectSameVoxels(on_cpu.voxels(), gpu_copy.voxels());
}

// A frame whose blocks overflow a small table: both devices refuse the same blocks and count them alike.
TEST(EngineCudaCapacityTest, FullTablesFailTheSameBlocks) {
    VF_SKIP_IF_UNAVAILABLE(Device::CUDA);
    const SceneParams params = test::centimetreSceneParams();
    VoxelBlockHashSettings s;
    s.bucket_count = 64;
    s.excess_entry_count = 200;
    s.max_block_count = 150;
    s.blocks_per_growth = 64;
    Scene<VoxelS, VoxelBlockHash> on_cpu(params, VoxelBlockHash(s, Device::CPU), Device::CPU);
    Scene<VoxelS, VoxelBlockHash> on_gpu(params, VoxelBlockHash(s, Device::CUDA), Device::CUDA);
    auto cpu_allocation = makeAllocationEngine<VoxelS, VoxelBlockHash>(Device::CPU);
    auto gpu_allocation = makeAllocationEngine<VoxelS, VoxelBlockHash>(Device::CUDA);
    for (const Mat4f& pose : cameraPath()) {
        const View view = frameView(pose, 0);
        const AllocationStats a = cpu_allocation->allocate(on_cpu, view, pose),
                              b = gpu_allocation->allocate(on_gpu, view, pose);
        EXPECT_GT(a.allocation_failures_this_frame, 0);
        EXPECT_EQ(a.allocation_failures_this_frame, b.allocation_failures_this_frame);
        EXPECT_EQ(a.failures_hash_full_this_frame, b.failures_hash_full_this_frame);
        EXPECT_EQ(a.failures_blocks_full_this_frame, b.failures_blocks_full_this_frame);
    }
    const auto gpu_copy = test::onHost(on_gpu);
    EXPECT_EQ(test::firstDifferentEntry(on_cpu.index(), gpu_copy.index()), -1);
}

}  // namespace
}  // namespace voxfuse
