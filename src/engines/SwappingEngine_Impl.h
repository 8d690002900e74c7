#pragma once
// The swapping engine's stages, written once for both device layers (see engines/SwappingEngine.h):
// a template on the device type, instantiated by src/cpu/SwappingEngine_CPU.cpp and
// cuda/SwappingEngine_CUDA.cu. Blocks cross between the device and the cache through transfer buffers
// of max_blocks blocks, allocated once (pinned host memory; a device copy on the GPU).

#include <algorithm>
#include <memory>
#include <vector>

#include "core/DeviceScratch.h"
#include "engines/DeviceImages.h"
#include "voxfuse/engines/SwappingEngine.h"
#include "voxfuse/shared/Swapping.h"

namespace voxfuse {

template <class TDevice, class TVoxel>
class SwappingEngineOn final : public SwappingEngine<TVoxel> {
    static constexpr Device kDevice = TDevice::kind;

public:
    int swapIn(Scene<TVoxel, VoxelBlockHash>& scene, GlobalCache& cache, int max_blocks) override {
        requireSceneOn(kDevice, scene, "the swapping engine");
        VoxelBlockHash& hash = scene.index();
        if (hash.storedBlocks() == 0 || max_blocks <= 0) return 0;
        // The copies of blocks this frame fuses first, then those only in the raycast's reach.
        int moved = moveIn(scene, cache, true, max_blocks, max_blocks);
        if (moved < max_blocks) moved += moveIn(scene, cache, false, max_blocks - moved, max_blocks);
        return moved;
    }

    int swapOut(Scene<TVoxel, VoxelBlockHash>& scene, GlobalCache& cache, int max_blocks) override {
        requireSceneOn(kDevice, scene, "the swapping engine");
        VoxelBlockHash& hash = scene.index();
        if (max_blocks <= 0) return 0;
        Mat4f T_world_camera;
        Intrinsics intrinsics;
        RaycastReach reach;
        if (hash.visibleListViewpoint(T_world_camera, intrinsics))
            reach = raycastReach(scene.params(), intrinsics, T_world_camera);
        int moved = moveOut(scene, cache, reach, false, max_blocks, max_blocks);
        // Blocks in the raycast's reach stay only while the array keeps room for the view beyond them;
        // past that the room's shortfall of them goes too.
        const int room = hash.settings().max_block_count - hash.blocksInUse();
        const int shortfall = reachReserveBlocks(hash.visibleCount()) - room;
        if (shortfall > 0 && moved < max_blocks)
            moved += moveOut(scene, cache, reach, true, std::min(shortfall, max_blocks - moved), max_blocks);
        return moved;
    }

private:
    // Merges the waiting copies of up to max_blocks blocks in (visible) or out of the visible list, through
    // transfer buffers of transfer_blocks (the call's bound, so that they keep their size).
    int moveIn(Scene<TVoxel, VoxelBlockHash>& scene, GlobalCache& cache, bool visible, int max_blocks,
               int transfer_blocks) {
        VoxelBlockHash& hash = scene.index();
        const HashTableState table = hash.state();
        const int count = select(
            hash, EntryMergePending{table.entries, table.stored_slot, table.entry_visibility, visible}, max_blocks);
        if (count == 0) return 0;
        prepareTransfer(cache, transfer_blocks);
        TDevice::parallelFor(count, GatherStoredSlots{listed_.data(kDevice), table.stored_slot, slots_.data(kDevice)});
        slots_.readRange(kDevice, 0, slots_host_.data(), std::size_t(count));
        cache.take(slots_host_.data(), count, transfer_.host());
        if (kDevice == Device::CUDA)
            transfer_.writeRange(kDevice, 0, transfer_.host(), std::size_t(count) * kBlockVoxelCount);
        TDevice::parallelFor(count * kBlockVoxelCount,
                             MergeStoredBlocks<TVoxel>{scene.voxelData(), table.entries, listed_.data(kDevice),
                                                       transfer_.data(kDevice), scene.params().max_weight});
        TDevice::parallelFor(count, ClearStoredSlots{listed_.data(kDevice), table.stored_slot});
        hash.addStoredBlocks(-count);
        return count;
    }

    // Moves up to max_blocks of the blocks EntryCanSwapOut{reach, in_reach} selects to the cache, through
    // transfer buffers of transfer_blocks (the call's bound, so that they keep their size).
    int moveOut(Scene<TVoxel, VoxelBlockHash>& scene, GlobalCache& cache, const RaycastReach& reach, bool in_reach,
                int max_blocks, int transfer_blocks) {
        VoxelBlockHash& hash = scene.index();
        const HashTableState table = hash.state();
        const int count = select(hash,
                                 EntryCanSwapOut<TVoxel>{table.entries, table.entry_visibility, table.stored_slot,
                                                         scene.voxelData(), reach, in_reach},
                                 max_blocks);
        if (count == 0) return 0;
        prepareTransfer(cache, transfer_blocks);
        TDevice::parallelFor(count * kBlockVoxelCount,
                             GatherBlockVoxels<TVoxel>{scene.voxelData(), table.entries, listed_.data(kDevice),
                                                       transfer_.data(kDevice)});
        if (kDevice == Device::CUDA)
            transfer_.readRange(kDevice, 0, transfer_.host(), std::size_t(count) * kBlockVoxelCount);
        cache.store(transfer_.host(), count, slots_host_.data());
        slots_.writeRange(kDevice, 0, slots_host_.data(), std::size_t(count));
        TDevice::parallelFor(count,
                             MarkSwappedOut{table, listed_.data(kDevice), slots_.data(kDevice), hash.freeBlocks()});
        hash.popFreeStacks(-count, 0);
        hash.addStoredBlocks(count);
        AllocationStats& stats = hash.stats();
        stats.blocks_allocated = hash.blocksInUse();
        return count;
    }

    // The first `max_blocks` entries (in entry order) that `pred` selects, into listed_; how many.
    template <class Pred>
    int select(const VoxelBlockHash& hash, const Pred& pred, int max_blocks) {
        if (listed_.size() < std::size_t(hash.entryCount()))
            listed_.allocate(std::size_t(hash.entryCount()), kDevice == Device::CPU, kDevice == Device::CUDA);
        const int found = TDevice::selectIndices(hash.entryCount(), pred, listed_.data(kDevice), scratch_);
        return std::min(found, max_blocks);
    }

    // The fixed-size transfer buffers, for max_blocks blocks.
    void prepareTransfer(const GlobalCache& cache, int max_blocks) {
        if (cache.blockBytes() != sizeof(TVoxel) * kBlockVoxelCount)
            throw ConfigError("swapping: the global cache holds blocks of " + std::to_string(cache.blockBytes()) +
                              " bytes, not " + std::to_string(sizeof(TVoxel) * kBlockVoxelCount));
        const std::size_t voxels = std::size_t(max_blocks) * kBlockVoxelCount;
        if (transfer_.size() != voxels) transfer_.allocate(voxels, true, kDevice == Device::CUDA, HostMemory::Pinned);
        if (slots_.size() != std::size_t(max_blocks))
            slots_.allocate(std::size_t(max_blocks), kDevice == Device::CPU, kDevice == Device::CUDA);
        slots_host_.resize(std::size_t(max_blocks));
    }

    DeviceScratch scratch_{kDevice};
    MemoryBlock<int> listed_;       // entries selected this call
    MemoryBlock<TVoxel> transfer_;  // the transfer buffer: host (pinned) and, on the GPU, device
    MemoryBlock<int> slots_;        // cache slots of the listed blocks, on the device
    std::vector<int> slots_host_;
};

template <class TDevice, class TVoxel>
std::unique_ptr<SwappingEngine<TVoxel>> makeSwappingEngineOn() {
    return std::make_unique<SwappingEngineOn<TDevice, TVoxel>>();
}

}  // namespace voxfuse
