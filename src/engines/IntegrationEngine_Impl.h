#pragma once
// The integration engine's stages, written once for both device layers: a template on the device type
// (CpuDevice or CudaDevice), instantiated by src/cpu/IntegrationEngine_CPU.cpp and
// cuda/IntegrationEngine_CUDA.cu. Every voxel update is integrateVoxel() (shared/Integration.h).
// The launch shapes differ: the CPU runs a whole hash block per element, and for the dense index
// frustum-clipped rows (IntegrateDenseRow: only voxels inside the frustum are visited); the GPU one
// voxel per thread (coalesced reads and writes).

#include <algorithm>
#include <memory>
#include <type_traits>

#include "core/DeviceScratch.h"
#include "cpu/IntegrationShapes_CPU.h"
#include "engines/DeviceImages.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/engines/IntegrationEngine.h"
#include "voxfuse/objects/PlainVoxelArray.h"
#include "voxfuse/objects/VoxelBlockHash.h"

namespace voxfuse {

template <class TDevice, class TVoxel, class TIndex>
class IntegrationEngineOn;

// The frame as the device sees it: the view's images on kDevice (colour and classes only for voxels
// that store them).
template <class TVoxel>
class IntegrationInputs {
public:
    IntegrationFrame frame(Device where, const SceneParams& params, const View& view, const Mat4f& T_world_camera,
                           std::uint32_t integration_number) {
        const float* depth = imageOn(where, view.depth, depth_);
        const Vec4u8* rgb = TVoxel::hasColor ? imageOn(where, view.rgb, rgb_) : nullptr;
        const ClassId* labels = TVoxel::hasLabel ? imageOn(where, view.labels, labels_) : nullptr;
        return makeIntegrationFrame(params, view, T_world_camera, depth, rgb, labels, integration_number);
    }

private:
    MemoryBlock<float> depth_;
    MemoryBlock<Vec4u8> rgb_;
    MemoryBlock<ClassId> labels_;
};

template <class TDevice, class TVoxel>
class IntegrationEngineOn<TDevice, TVoxel, PlainVoxelArray> final : public IntegrationEngine<TVoxel, PlainVoxelArray> {
    static constexpr Device kDevice = TDevice::kind;

public:
    void integrate(Scene<TVoxel, PlainVoxelArray>& scene, const View& view, const Mat4f& T_world_camera) override {
        requireSceneOn(kDevice, scene, "the integration engine");
        const PlainVoxelArray::Data index = scene.index().data();
        const std::uint32_t integration_number = scene.takeIntegrationNumber();
        const IntegrationFrame frame = inputs_.frame(kDevice, scene.params(), view, T_world_camera, integration_number);
        const float max_depth_m =
            TDevice::maxOf(int(view.depth.pixelCount()), UsableDepth{frame.depth, frame.min_depth_m, frame.max_depth_m},
                           0.f, scratch_);
        Vec3i lo, hi;  // array coordinates (not offset)
        float far_m;
        if (!denseIntegrationBox(index, scene.params(), view.calib.depth, T_world_camera, max_depth_m, lo, hi, far_m))
            return;
        if constexpr (!TDevice::kOneThreadPerItem) {
            TDevice::parallelFor((hi.y - lo.y) * (hi.z - lo.z),
                                 IntegrateDenseRow<TVoxel>{scene.voxelData(), index, lo, hi, far_m, frame});
        } else {
            // Slabs of whole z-slices, each at most 2^30 voxels (element indices are ints).
            const Vec3i box = hi - lo;
            const int slices_per_launch = std::max(1, (1 << 30) / (box.x * box.y));
            for (int z = 0; z < box.z; z += slices_per_launch) {
                const int slices = std::min(slices_per_launch, box.z - z);
                TDevice::parallelFor(box.x * box.y * slices,
                                     IntegrateDenseVoxel<TVoxel>{scene.voxelData(), index, lo, box, z, frame});
            }
        }
    }

    void resetScene(Scene<TVoxel, PlainVoxelArray>& scene) override {
        requireSceneOn(kDevice, scene, "the integration engine");
        scene.voxels().fill(kDevice, TVoxel::initial(), 0, scene.voxels().size());
    }

private:
    IntegrationInputs<TVoxel> inputs_;
    DeviceScratch scratch_{kDevice};
};

// The hash: every voxel of the blocks in the visible list, which the allocation engine built for this view.
template <class TDevice, class TVoxel>
class IntegrationEngineOn<TDevice, TVoxel, VoxelBlockHash> final : public IntegrationEngine<TVoxel, VoxelBlockHash> {
    static constexpr Device kDevice = TDevice::kind;

public:
    void integrate(Scene<TVoxel, VoxelBlockHash>& scene, const View& view, const Mat4f& T_world_camera) override {
        requireSceneOn(kDevice, scene, "the integration engine");
        const VoxelBlockHash& hash = scene.index();
        if (!hash.visibleListCovers(T_world_camera, view.calib.depth))
            throw Error(
                "hash integration: the visible list is not for this view (run the allocation engine on it first)");
        const IntegrationFrame frame =
            inputs_.frame(kDevice, scene.params(), view, T_world_camera, scene.takeIntegrationNumber());
        const int blocks = keepBlocksToUpdate(hash, scene.params(), view.calib.depth, frame);
        using Body =
            std::conditional_t<TDevice::kOneThreadPerItem, IntegrateHashVoxels<TVoxel, 1>, IntegrateHashBlocks<TVoxel>>;
        // At most 2^30 elements per launch (element indices are ints).
        const int blocks_per_launch = (1 << 30) / Body::kElementsPerBlock;
        for (int first = 0; first < blocks; first += blocks_per_launch) {
            const int count = std::min(blocks_per_launch, blocks - first);
            TDevice::parallelFor(Body::elementCount(count), Body{scene.voxelData(), hash.data().entries,
                                                                 kept_entries_.data(kDevice) + first, count, frame});
        }
    }

    // Frees every block and returns the voxel storage to its initial (empty) size.
    void resetScene(Scene<TVoxel, VoxelBlockHash>& scene) override {
        requireSceneOn(kDevice, scene, "the integration engine");
        scene.clearVoxelBlocks();
    }

private:
    // The entries of the visible blocks some voxel of which the frame may update, into kept_entries_
    // (BlockNeedsIntegration); returns how many.
    int keepBlocksToUpdate(const VoxelBlockHash& hash, const SceneParams& params, const Intrinsics& camera,
                           const IntegrationFrame& frame) {
        const int visible = hash.visibleCount();
        if (visible == 0) return 0;
        const int tiles_x = (camera.width + kDepthTile - 1) / kDepthTile,
                  tiles_y = (camera.height + kDepthTile - 1) / kDepthTile;
        grow(tile_max_, std::size_t(tiles_x) * std::size_t(tiles_y));
        grow(keep_, std::size_t(visible));
        grow(kept_positions_, std::size_t(visible));
        grow(kept_entries_, std::size_t(visible));
        TDevice::parallelFor(tiles_x * tiles_y, DepthMaxTiles{frame.depth, camera.size(), frame.min_depth_m,
                                                              frame.max_depth_m, tiles_x, tile_max_.data(kDevice)});
        const BlockProjection projection{frame.T_depth_world, camera, params.voxel_size_m, frame.near_m,
                                         frame.max_depth_m + params.mu_m};
        TDevice::parallelFor(visible,
                             BlockNeedsIntegration{hash.data().entries, hash.visibleEntries(), projection, params.mu_m,
                                                   tile_max_.data(kDevice), tiles_x, tiles_y, keep_.data(kDevice)});
        const int kept =
            TDevice::selectIndices(visible, BlockIsKept{keep_.data(kDevice)}, kept_positions_.data(kDevice), scratch_);
        TDevice::parallelFor(
            kept, GatherEntries{hash.visibleEntries(), kept_positions_.data(kDevice), kept_entries_.data(kDevice)});
        return kept;
    }

    template <class T>
    static void grow(MemoryBlock<T>& block, std::size_t count) {
        if (block.size() < count) block.allocate(count, kDevice == Device::CPU, kDevice == Device::CUDA);
    }

    IntegrationInputs<TVoxel> inputs_;
    DeviceScratch scratch_{kDevice};
    MemoryBlock<float> tile_max_;
    MemoryBlock<unsigned char> keep_;
    MemoryBlock<int> kept_positions_, kept_entries_;
};

template <class TDevice, class TVoxel, class TIndex>
std::unique_ptr<IntegrationEngine<TVoxel, TIndex>> makeIntegrationEngineOn() {
    return std::make_unique<IntegrationEngineOn<TDevice, TVoxel, TIndex>>();
}

}  // namespace voxfuse
