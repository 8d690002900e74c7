// CPU and CUDA integration call the same integrateVoxel(): on the same frames they must produce the
// same voxels, bit for bit in every channel, classes included (their random numbers hash the voxel
// position and the frame).
// Skips visibly when no GPU is usable.

#include <gtest/gtest.h>

#include <utility>

#include "DeviceTestSupport.h"
#include "SyntheticViews.h"
#include "voxfuse/engines/IntegrationEngine.h"
#include "voxfuse/objects/Voxel.h"

namespace voxfuse {
namespace {

template <class TVoxel>
class IntegrationCudaParityTest : public ::testing::Test {};
using VoxelTypes = ::testing::Types<VoxelS, VoxelF, VoxelSRgb, VoxelFRgb, VoxelSLabel, VoxelSRgbLabel>;
TYPED_TEST_SUITE(IntegrationCudaParityTest, VoxelTypes);

TYPED_TEST(IntegrationCudaParityTest, CpuAndCudaGiveTheSameVoxels) {
    using TVoxel = TypeParam;
    if (!device_memory::cudaAvailable()) GTEST_SKIP() << "no usable GPU: " << device_memory::cudaDescription();

    SceneParams params;
    params.voxel_size_m = 0.01f;
    params.mu_m = 0.04f;
    const PlainVoxelArray index({-60, -60, -20}, {140, 120, 80});
    Scene<TVoxel, PlainVoxelArray> on_cpu(params, index, Device::CPU);
    Scene<TVoxel, PlainVoxelArray> on_gpu(params, index, Device::CUDA);
    auto cpu_engine = makeIntegrationEngine<TVoxel, PlainVoxelArray>(Device::CPU);
    auto gpu_engine = makeIntegrationEngine<TVoxel, PlainVoxelArray>(Device::CUDA);

    const synth::SyntheticScene world = synth::SyntheticScene::boxAndSphere();
    const Intrinsics intr = test::kinectIntrinsics(320, 240);
    for (int k = 0; k < 4; ++k) {
        const Mat4f pose = test::lookAt({0.9f - 0.2f * k, -0.7f + 0.3f * k, 0.8f}, {0.2f, 0.f, 0.1f});
        View view = test::labelledView(world, intr, pose, k);
        view.frame_index = k;
        cpu_engine->integrate(on_cpu, view, pose);
        gpu_engine->integrate(on_gpu, view, pose);
    }
    // The scene lives on the GPU only: its host copy is made here, for the comparison.
    on_gpu.voxels().updateHost();
    const auto& gpu_voxels = std::as_const(on_gpu).voxels();
    const auto& cpu_voxels = std::as_const(on_cpu).voxels();

    // Same function, same inputs, no fused multiply-adds: every channel of every voxel, bit for bit.
    long long observed = 0, labelled = 0;
    for (std::size_t i = 0; i < cpu_voxels.size(); ++i) {
        observed += cpu_voxels.host()[i].w_depth > 0;
        if constexpr (TVoxel::hasLabel) labelled += cpu_voxels.host()[i].w_label > 0;
    }
    EXPECT_GT(observed, 10000);
    if constexpr (TVoxel::hasLabel) {
        EXPECT_GT(labelled, 1000) << "the label path ran";
    }
    const test::ChannelDifferences d = test::voxelDifferences(cpu_voxels, gpu_voxels);
    EXPECT_TRUE(d.none()) << d.describe();

    gpu_engine->resetScene(on_gpu);
    on_gpu.voxels().updateHost();
    for (std::size_t i = 0; i < gpu_voxels.size(); ++i) ASSERT_EQ(gpu_voxels.host()[i].w_depth, 0);
}

}  // namespace
}  // namespace voxfuse
