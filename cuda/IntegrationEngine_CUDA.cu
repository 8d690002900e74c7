// CUDA layer of the integration engine: one thread per voxel of the frustum box, each calling the
// same integrateVoxel() (shared/Integration.h) as the CPU loop.

#include "CudaCheck.h"
#include "voxfuse/engines/IntegrationEngine.h"
#include "voxfuse/engines/EnginePairs.h"
#include "voxfuse/objects/Voxel.h"
#include "voxfuse/objects/VoxelBlockHash.h"

namespace voxfuse::cuda {
namespace {

template <class TVoxel>
__global__ void integrateDenseKernel(TVoxel* voxels, PlainVoxelArray::Data index, Vec3i lo, Vec3i hi, IntegrationFrame frame) {
    const int x = lo.x + int(blockIdx.x * blockDim.x + threadIdx.x);
    const int y = lo.y + int(blockIdx.y * blockDim.y + threadIdx.y);
    const int z = lo.z + int(blockIdx.z * blockDim.z + threadIdx.z);
    if (x >= hi.x || y >= hi.y || z >= hi.z) return;
    integrateVoxel(voxels[x + (long long)index.size.x * (y + (long long)index.size.y * z)], Vec3i{x, y, z} + index.offset, frame);
}

template <class TVoxel>
__global__ void fillKernel(TVoxel* voxels, long long count, TVoxel value) {
    const long long i = (long long)blockIdx.x * blockDim.x + threadIdx.x;
    if (i < count) voxels[i] = value;
}

template <class TVoxel, class TIndex>
class IntegrationEngine_CUDA;

template <class TVoxel>
class IntegrationEngine_CUDA<TVoxel, PlainVoxelArray> final : public IntegrationEngine<TVoxel, PlainVoxelArray> {
public:
    void integrate(Scene<TVoxel, PlainVoxelArray>& scene, const View& view, const Mat4f& T_world_camera) override {
        requireDeviceScene(scene);
        const PlainVoxelArray::Data index = scene.index().data();
        const std::uint32_t integration_number = scene.takeIntegrationNumber();
        Vec3i lo, hi;
        float far_m;
        if (!denseIntegrationBox(index, scene.params(), view, T_world_camera, lo, hi, far_m)) return;

        // The frame goes to the GPU once; the scene already lives there.
        depth_.allocate(view.depth.pixelCount(), false, true);
        device_memory::copyHostToDevice(depth_.device(), view.depth.host(), view.depth.pixelCount() * sizeof(float));
        const Vec4u8* rgb = nullptr;
        if (TVoxel::hasColor && !view.rgb.empty()) {
            rgb_.allocate(view.rgb.pixelCount(), false, true);
            device_memory::copyHostToDevice(rgb_.device(), view.rgb.host(), view.rgb.pixelCount() * sizeof(Vec4u8));
            rgb = rgb_.device();
        }
        const ClassId* labels = nullptr;
        if (TVoxel::hasLabel && !view.labels.empty()) {
            labels_.allocate(view.labels.pixelCount(), false, true);
            device_memory::copyHostToDevice(labels_.device(), view.labels.host(), view.labels.pixelCount() * sizeof(ClassId));
            labels = labels_.device();
        }
        const IntegrationFrame frame = makeIntegrationFrame(scene.params(), view, T_world_camera, depth_.device(), rgb, labels, integration_number);

        const dim3 block(32, 4, 2);
        const dim3 grid(blocksFor(hi.x - lo.x, block.x), blocksFor(hi.y - lo.y, block.y), blocksFor(hi.z - lo.z, block.z));
        integrateDenseKernel<<<grid, block>>>(scene.voxels().device(), index, lo, hi, frame);
        VF_CUDA_CHECK_LAUNCH();
        VF_CUDA_CHECK(cudaDeviceSynchronize());
    }

    void resetScene(Scene<TVoxel, PlainVoxelArray>& scene) override {
        requireDeviceScene(scene);
        const long long n = (long long)scene.voxels().size();
        fillKernel<<<unsigned((n + 255) / 256), 256>>>(scene.voxels().device(), n, TVoxel::initial());
        VF_CUDA_CHECK_LAUNCH();
        VF_CUDA_CHECK(cudaDeviceSynchronize());
    }

private:
    static void requireDeviceScene(const Scene<TVoxel, PlainVoxelArray>& scene) {
        if (scene.location() != Device::CUDA || !scene.voxels().onDevice())
            throw DeviceError("the CUDA integration engine needs a scene allocated on the GPU (Device::CUDA)");
    }

    MemoryBlock<float> depth_;
    MemoryBlock<Vec4u8> rgb_;
    MemoryBlock<ClassId> labels_;
};

// The hash has no CUDA layer yet: the factory exists so that every pair links, and says so when used.
template <class TVoxel>
class IntegrationEngine_CUDA<TVoxel, VoxelBlockHash> final : public IntegrationEngine<TVoxel, VoxelBlockHash> {
public:
    IntegrationEngine_CUDA() { throw DeviceError("the voxel block hash has no CUDA integration yet: use the CPU device"); }
    void integrate(Scene<TVoxel, VoxelBlockHash>&, const View&, const Mat4f&) override {}
    void resetScene(Scene<TVoxel, VoxelBlockHash>&) override {}
};

}  // namespace

template <class TVoxel, class TIndex>
std::unique_ptr<IntegrationEngine<TVoxel, TIndex>> makeIntegrationEngine() {
    return std::make_unique<IntegrationEngine_CUDA<TVoxel, TIndex>>();
}

#define VF_INSTANTIATE(TVoxel, TIndex) template std::unique_ptr<IntegrationEngine<TVoxel, TIndex>> makeIntegrationEngine<TVoxel, TIndex>();
VF_FOR_EACH_ENGINE_PAIR(VF_INSTANTIATE)
#undef VF_INSTANTIATE

}  // namespace voxfuse::cuda
