// Marching cubes and the point cloud on the GPU against the CPU layer, on the same map (fused on the
// CPU, copied to the GPU), for every voxel type and both indexes. Both devices run the same loop
// bodies in the same block order and, built without fused multiply-adds, round alike: the meshes must
// be the same bit for bit (triangles index for index; every channel of vertices, normals, colours and
// classes), and so must the clouds. Skips visibly without a GPU.

#include <gtest/gtest.h>

#include <algorithm>
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

// Every channel of every element, bit for bit (Vec3f, Vec3u8, Vec3i: three channels; classes: one).
template <class T, int Channels>
void expectSameArray(const std::vector<T>& a, const std::vector<T>& b, const char* what) {
    ASSERT_EQ(a.size(), b.size()) << what;
    test::ChannelDifferences d;
    test::addImageDifferences<T, Channels>(d, what, a.data(), b.data(), a.size());
    EXPECT_TRUE(d.none()) << d.describe();
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
    expectSameArray<Vec3i, 3>(mc.triangles, mg.triangles, "triangle");
    expectSameArray<Vec3f, 3>(mc.vertices, mg.vertices, "vertex");
    expectSameArray<Vec3f, 3>(mc.normals, mg.normals, "normal");
    expectSameArray<Vec3u8, 3>(mc.colors, mg.colors, "colour");
    expectSameArray<ClassId, 1>(mc.labels, mg.labels, "class");

    PointCloud cc, cg;
    cpu->extractPointCloud(on_cpu, cc);
    gpu->extractPointCloud(on_gpu, cg);
    expectSameArray<Vec3f, 3>(cc.points, cg.points, "cloud point");
    expectSameArray<Vec3f, 3>(cc.normals, cg.normals, "cloud normal");
    expectSameArray<Vec3u8, 3>(cc.colors, cg.colors, "cloud colour");
    expectSameArray<Vec3f, 3>(mg.vertices, cg.points, "cloud point against the mesh's vertex");
    expectSameArray<ClassId, 1>(cc.labels, cg.labels, "cloud class");
}

TYPED_TEST(MeshingCudaParityTest, HashMapGivesTheSameMeshAndCloud) {
    Scene<TypeParam, VoxelBlockHash> scene(test::centimetreSceneParams(),
                                           VoxelBlockHash(VoxelBlockHashSettings(), Device::CPU), Device::CPU);
    fuseOnCpu(scene);
    expectSameSurfaceOnBothDevices(scene);
}

TYPED_TEST(MeshingCudaParityTest, DenseMapGivesTheSameMeshAndCloud) {
    // An array whose sides are not multiples of a block: blocks at its border are partly outside.
    Scene<TypeParam, PlainVoxelArray> scene(test::centimetreSceneParams(),
                                            PlainVoxelArray({-83, -77, -21}, {181, 163, 101}), Device::CPU);
    fuseOnCpu(scene);
    expectSameSurfaceOnBothDevices(scene);
}

}  // namespace
}  // namespace voxfuse
