// Marching cubes and the point cloud on the GPU against the CPU layer, on the same map (fused on the
// CPU, copied to the GPU), for every voxel type and both indexes. Both devices run the same loop
// bodies in the same block order and, built without fused multiply-adds, round alike: the meshes must
// have the same triangles, index for index, and vertices, normals, colours and classes that agree to
// float rounding. Skips visibly without a GPU.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <type_traits>
#include <vector>

#include "DeviceTestSupport.h"
#include "SyntheticViews.h"
#include "voxfuse/engines/AllocationEngine.h"
#include "voxfuse/engines/IntegrationEngine.h"
#include "voxfuse/engines/MeshingEngine.h"
#include "voxfuse/objects/Voxel.h"

namespace voxfuse {
namespace {

template <class TVoxel>
class MeshingCudaParityTest : public ::testing::Test {
protected:
    void SetUp() override { VF_SKIP_IF_UNAVAILABLE(Device::CUDA); }
};
using VoxelTypes = ::testing::Types<VoxelS, VoxelF, VoxelSRgb, VoxelFRgb, VoxelSLabel, VoxelSRgbLabel>;
TYPED_TEST_SUITE(MeshingCudaParityTest, VoxelTypes);

template <class TVoxel, class TIndex>
void fuseOnCpu(Scene<TVoxel, TIndex>& scene) {
    static const synth::SyntheticScene world = synth::SyntheticScene::boxAndSphere();
    auto allocation = makeAllocationEngine<TVoxel, TIndex>(Device::CPU);
    auto integration = makeIntegrationEngine<TVoxel, TIndex>(Device::CPU);
    for (int k = 0; k < 4; ++k) {
        const Mat4f pose = test::lookAt({1.0f - 0.2f * k, -0.8f + 0.4f * k, 0.8f}, {0.2f, 0.f, 0.1f});
        const View view = test::labelledView(world, test::kinectIntrinsics(320, 240), pose, k);
        if constexpr (std::is_same<TIndex, VoxelBlockHash>::value) allocation->allocate(scene, view, pose);
        integration->integrate(scene, view, pose);
    }
}

float largestDifference(const std::vector<Vec3f>& a, const std::vector<Vec3f>& b) {
    float d = 0.f;
    for (std::size_t i = 0; i < a.size(); ++i) d = std::max(d, length(a[i] - b[i]));
    return d;
}

template <class TVoxel, class TIndex>
void expectSameSurfaceOnBothDevices(const Scene<TVoxel, TIndex>& on_cpu) {
    const Scene<TVoxel, TIndex> on_gpu = on_cpu.copyTo(Device::CUDA);
    auto cpu = makeMeshingEngine<TVoxel, TIndex>(Device::CPU);
    auto gpu = makeMeshingEngine<TVoxel, TIndex>(Device::CUDA);
    Mesh mc, mg;
    cpu->extractMesh(on_cpu, mc);
    gpu->extractMesh(on_gpu, mg);
    ASSERT_GT(mc.triangles.size(), 20000u);
    ASSERT_EQ(mc.vertices.size(), mg.vertices.size());
    ASSERT_EQ(mc.triangles.size(), mg.triangles.size());
    EXPECT_TRUE(std::equal(mc.triangles.begin(), mc.triangles.end(), mg.triangles.begin())) << "the same triangles, index for index";
    EXPECT_LE(largestDifference(mc.vertices, mg.vertices), 1e-6f) << "vertices (m)";
    EXPECT_LE(largestDifference(mc.normals, mg.normals), 1e-5f) << "normals";
    ASSERT_EQ(mc.colors.size(), mg.colors.size());
    for (std::size_t i = 0; i < mc.colors.size(); ++i)
        for (int c = 0; c < 3; ++c) ASSERT_LE(std::abs(int(mc.colors[i][c]) - int(mg.colors[i][c])), 1) << "colour " << i;
    EXPECT_EQ(mc.labels, mg.labels);

    PointCloud cc, cg;
    cpu->extractPointCloud(on_cpu, cc);
    gpu->extractPointCloud(on_gpu, cg);
    ASSERT_EQ(cg.points.size(), mg.vertices.size()) << "the cloud is the mesh's vertices";
    EXPECT_LE(largestDifference(cg.points, mg.vertices), 0.f);
    EXPECT_EQ(cc.labels, cg.labels);
}

TYPED_TEST(MeshingCudaParityTest, HashMapGivesTheSameMeshAndCloud) {
    Scene<TypeParam, VoxelBlockHash> scene(test::centimetreSceneParams(), VoxelBlockHash(VoxelBlockHashSettings(), Device::CPU), Device::CPU);
    fuseOnCpu(scene);
    expectSameSurfaceOnBothDevices(scene);
}

TYPED_TEST(MeshingCudaParityTest, DenseMapGivesTheSameMeshAndCloud) {
    // An array whose sides are not multiples of a block: blocks at its border are partly outside.
    Scene<TypeParam, PlainVoxelArray> scene(test::centimetreSceneParams(), PlainVoxelArray({-83, -77, -21}, {181, 163, 101}), Device::CPU);
    fuseOnCpu(scene);
    expectSameSurfaceOnBothDevices(scene);
}

}  // namespace
}  // namespace voxfuse
