#pragma once
// The stages of hash allocation and block removal, written once for both device layers: a template
// on the device type (CpuDevice or CudaDevice), instantiated by src/cpu/AllocationEngine_CPU.cpp and
// cuda/AllocationEngine_CUDA.cu. Each stage is a launch of a loop body from shared/Allocation.h or
// shared/HashUpdate.h, or a primitive of the device (scan, selection, sort). Only the shape of
// stage 1 differs between the devices: the CPU runs a tile per element with a cache of the blocks
// already handled, the GPU a tile per team of threads that share the set of blocks handled.

#include <algorithm>
#include <climits>
#include <cstdint>
#include <memory>

#include "core/DeviceScratch.h"
#include "cpu/AllocationShapes_CPU.h"
#include "engines/DeviceImages.h"
#include "voxfuse/engines/AllocationEngine.h"
#include "voxfuse/engines/IntegrationEngine.h"
#include "voxfuse/shared/Allocation.h"
#include "voxfuse/shared/BlockProjection.h"
#include "voxfuse/shared/HashUpdate.h"
#include "voxfuse/shared/Swapping.h"

namespace voxfuse {

// The dense index has every voxel already: nothing to allocate or remove, on any device.
template <class TVoxel>
class DenseAllocationEngine final : public AllocationEngine<TVoxel, PlainVoxelArray> {
public:
    AllocationStats allocate(Scene<TVoxel, PlainVoxelArray>&, const View&, const Mat4f&) override {
        return AllocationStats();
    }
    int removeEmptyBlocks(Scene<TVoxel, PlainVoxelArray>&) override { return 0; }
};

template <class TDevice, class TVoxel>
class HashAllocationEngine final : public AllocationEngine<TVoxel, VoxelBlockHash> {
    static constexpr Device kDevice = TDevice::kind;

public:
    AllocationStats allocate(Scene<TVoxel, VoxelBlockHash>& scene, const View& view,
                             const Mat4f& T_world_camera) override {
        requireSceneOn(kDevice, scene, "the hash allocation engine");
        VoxelBlockHash& hash = scene.index();
        AllocationStats& stats = hash.stats();
        stats.blocks_allocated_this_frame = 0;
        stats.allocation_failures_this_frame = stats.failures_hash_full_this_frame =
            stats.failures_blocks_full_this_frame = 0;
        stats.missing_block_appends_this_frame = stats.stage1_passes_this_frame = 0;

        DepthSegmentFrame frame = makeDepthSegmentFrame(scene.params(), view, T_world_camera);
        frame.depth = imageOn(kDevice, view.depth, depth_staging_);
        bool out_of_range = false;
        // One pass, unless the list of missing blocks overflowed its bound: then the blocks it held go
        // in, and the pass repeats for the rest while that makes progress.
        for (;;) {
            const int appended = markBlocks(hash, frame, stats);
            const int stored = std::min(appended, int(missing_.size()));
            int distinct = TDevice::sortUnique(on(missing_), stored, scratch_);
            if (distinct > 0 && TDevice::read(on(missing_) + distinct - 1, scratch_) == kOutOfRangeBlockKey) {
                out_of_range = true;
                --distinct;
            }
            // A growable table first grows to hold them (stage 1 keeps no entry index, only keys).
            if (hash.wantsMoreBuckets(distinct)) hash.growBuckets(distinct);
            const int inserted = insertMissingBlocks(scene, distinct, stats);
            if (appended <= stored) break;
            if (inserted == 0) {
                // Nothing fits any more; what the list could not hold is counted as visits, an upper bound
                // (a lower one when the count saturated at kMaxCountedAppends).
                stats.allocation_failures_this_frame += appended - stored;
                break;
            }
        }
        if (hash.storedBlocks() > 0) {
            const RaycastReach reach = raycastReach(scene.params(), view.calib.depth, T_world_camera);
            stats.blocks_activated_this_frame = activateStoredBlocks(scene, reach, false, stats);
            stats.blocks_activated_this_frame += activateStoredBlocks(scene, reach, true, stats);
        } else {
            stats.blocks_activated_this_frame = 0;
        }
        buildVisibleList(hash, scene.params(), view, T_world_camera);

        stats.allocation_failures_this_frame +=
            stats.failures_hash_full_this_frame + stats.failures_blocks_full_this_frame + (out_of_range ? 1 : 0);
        stats.allocation_failures_total += stats.allocation_failures_this_frame;
        stats.blocks_allocated = hash.blocksInUse();
        stats.block_capacity = hash.blockCapacity();
        stats.visible_blocks = hash.visibleCount();
        return stats;
    }

    int removeEmptyBlocks(Scene<TVoxel, VoxelBlockHash>& scene) override {
        requireSceneOn(kDevice, scene, "the hash allocation engine");
        VoxelBlockHash& hash = scene.index();
        const int entries = hash.entryCount(), buckets = hash.settings().bucket_count;
        grow(remove_, entries);
        grow(freed_blocks_, buckets);
        grow(freed_excess_, buckets);
        const HashTableState table = hash.state();
        TDevice::parallelFor(entries,
                             MarkEmptyBlocks<TVoxel>{table.entries, table.stored_slot, scene.voxelData(), on(remove_)});
        const BucketRemoval count_pass{
            table, on(remove_), on(freed_blocks_), on(freed_excess_), hash.freeBlocks(), hash.freeExcessEntries()};
        TDevice::parallelFor(buckets, CountBucketRemovals{count_pass});
        const int freed_blocks = TDevice::exclusiveScan(on(freed_blocks_), on(freed_blocks_), buckets, scratch_);
        const int freed_excess = TDevice::exclusiveScan(on(freed_excess_), on(freed_excess_), buckets, scratch_);
        if (freed_blocks == 0) return 0;
        TDevice::parallelFor(buckets, RemoveBucketEntries{count_pass});
        hash.popFreeStacks(-freed_blocks, -freed_excess);
        AllocationStats& stats = hash.stats();
        stats.blocks_removed_total += freed_blocks;
        stats.blocks_allocated = hash.blocksInUse();
        // Removal moved visibility marks with their entries: the list is rebuilt from them.
        hash.setVisibleCount(TDevice::selectIndices(entries, EntryIsVisible{hash.entryVisibility()},
                                                    hash.visibleEntriesForWriting(), scratch_));
        return freed_blocks;
    }

private:
    template <class T>
    static T* on(MemoryBlock<T>& block) {
        return block.data(kDevice);
    }
    // At least `count` elements on the layer's device (contents kept only when no growth was needed).
    template <class T>
    static void grow(MemoryBlock<T>& block, std::size_t count) {
        if (block.size() < count) block.allocate(count, kDevice == Device::CPU, kDevice == Device::CUDA);
    }

    // Stage 1. Returns the appends attempted; the missing list holds the first min(that, its size).
    // The list starts at two blocks per depth pixel and grows to eight when a frame needs more (the
    // pass is then repeated: it only marks and lists).
    int markBlocks(VoxelBlockHash& hash, const DepthSegmentFrame& frame, AllocationStats& stats) {
        const int pixels = frame.intrinsics.width * frame.intrinsics.height;
        const int bound = 8 * pixels;
        grow(missing_, std::size_t(2) * std::size_t(pixels));
        grow(missing_count_, 1);
        for (;;) {
            TDevice::write(on(missing_count_), 0);
            const HashTableView table = hash.data();
            std::uint8_t* visibility = hash.state().entry_visibility;
            if constexpr (!TDevice::kOneThreadPerItem) {
                const MarkBlocksForPixels<256> mark{
                    frame, table, visibility, on(missing_), on(missing_count_), int(missing_.size()), Vec2i{32, 32}};
                TDevice::parallelFor(mark.elementCount(), mark);
            } else {
                const MarkBlocksForPixelTeams mark{
                    frame,
                    {table, visibility, on(missing_), on(missing_count_), int(missing_.size()), kMaxCountedAppends}};
                TDevice::template parallelForTeams<TileBlockSet>(mark.itemCount(), mark);
            }
            const int appended = TDevice::read(on(missing_count_), scratch_);
            ++stats.stage1_passes_this_frame;
            stats.missing_block_appends_this_frame = appended > INT_MAX - stats.missing_block_appends_this_frame
                                                         ? INT_MAX
                                                         : stats.missing_block_appends_this_frame + appended;
            if (appended <= int(missing_.size()) || int(missing_.size()) >= bound) return appended;
            missing_.allocate(std::size_t(std::min<long long>(bound, appended + appended / 4ll)),
                              kDevice == Device::CPU, kDevice == Device::CUDA);
        }
    }

    // Stage 2: inserts the `count` distinct missing blocks at the front of the missing list, in rounds
    // (shared/HashUpdate.h), and resets their voxels. Returns how many went in.
    int insertMissingBlocks(Scene<TVoxel, VoxelBlockHash>& scene, int count, AllocationStats& stats) {
        if (count == 0) return 0;
        VoxelBlockHash& hash = scene.index();
        if (count > hash.freeBlocks()) scene.reserveVoxelBlocks(hash.blocksInUse() + count);
        const std::size_t n = std::size_t(count);
        grow(target_, n);
        grow(outcome_, n);
        grow(needs_excess_, n);
        grow(excess_wanted_, n);
        grow(excess_rank_, n);
        grow(block_wanted_, n);
        grow(block_rank_, n);
        grow(counts_, 1);
        if (claim_.size() != std::size_t(hash.entryCount())) {
            claim_.allocate(std::size_t(hash.entryCount()), kDevice == Device::CPU, kDevice == Device::CUDA);
            claim_.fill(kDevice, INT_MAX, 0, claim_.size());  // every round gives its claims back
        }
        target_.fill(kDevice, -1, 0, n);
        outcome_.fill(kDevice, std::uint8_t(kInsertPending), 0, n);

        const int free_before = hash.freeBlocks();
        for (;;) {
            const InsertRound r{hash.state(),
                                on(missing_),
                                on(target_),
                                on(claim_),
                                on(outcome_),
                                on(needs_excess_),
                                on(excess_wanted_),
                                on(excess_rank_),
                                on(block_wanted_),
                                on(block_rank_),
                                on(counts_),
                                hash.freeBlocks(),
                                hash.freeExcessEntries()};
            TDevice::write(on(counts_), InsertRoundCounts{});
            TDevice::parallelFor(count, ClaimInsertTarget{r});
            TDevice::parallelFor(count, DecideInsertWinners{r});
            TDevice::exclusiveScan(r.excess_wanted, r.excess_rank, count, scratch_);
            TDevice::parallelFor(count, GrantInsertBlocks{r});
            TDevice::exclusiveScan(r.block_wanted, r.block_rank, count, scratch_);
            TDevice::parallelFor(count, InsertGrantedBlocks{r});
            TDevice::parallelFor(count, ReleaseInsertClaims{r});
            const InsertRoundCounts c = TDevice::read(on(counts_), scratch_);
            hash.popFreeStacks(c.inserted, c.excess_used);
            stats.failures_hash_full_this_frame += c.failed_hash;
            stats.failures_blocks_full_this_frame += c.failed_blocks;
            if (c.pending == 0) break;
        }
        // The blocks taken are the ones between the stack's old and new tops.
        const int inserted = free_before - hash.freeBlocks();
        resetBlocks(scene, hash.state().free_blocks + hash.freeBlocks(), inserted);
        stats.blocks_allocated_this_frame += inserted;
        return inserted;
    }

    // Swapping: stored blocks the depth needs (or, reach_only, that the raycast can read) get voxel blocks
    // again (merge pending), in entry order, while the voxel array has blocks; the others stay stored and
    // out of view (those the depth needs counted as blocks full). Returns how many were activated.
    int activateStoredBlocks(Scene<TVoxel, VoxelBlockHash>& scene, const RaycastReach& reach, bool reach_only,
                             AllocationStats& stats) {
        VoxelBlockHash& hash = scene.index();
        // Blocks only in the raycast's reach take no more than the room beyond the view's reserve
        // (the last visible list's size: this frame's is not made yet); without room, no pass over the table.
        const int reach_room =
            hash.settings().max_block_count - hash.blocksInUse() - reachReserveBlocks(hash.visibleCount());
        if (reach_only && reach_room <= 0) return 0;
        grow(activation_, std::size_t(hash.entryCount()));
        const HashTableState before = hash.state();
        const int count = TDevice::selectIndices(
            hash.entryCount(), EntryNeedsActivation{before.entries, before.entry_visibility, reach, reach_only},
            on(activation_), scratch_);
        if (count == 0) return 0;
        const int wanted = reach_only ? std::min(count, reach_room) : count;
        if (wanted > hash.freeBlocks()) scene.reserveVoxelBlocks(hash.blocksInUse() + wanted);
        const int activated = std::min(hash.freeBlocks(), wanted);
        TDevice::parallelFor(count, ActivateStoredBlocks{hash.state(), on(activation_), hash.freeBlocks(), activated});
        hash.popFreeStacks(activated, 0);
        if (!reach_only) stats.failures_blocks_full_this_frame += count - activated;
        resetBlocks(scene, hash.state().free_blocks + hash.freeBlocks(), activated);
        return activated;
    }

    // Blocks come off the free stack with old contents: the `count` blocks listed at `taken` start afresh.
    static void resetBlocks(Scene<TVoxel, VoxelBlockHash>& scene, const int* taken, int count) {
        constexpr int kBlocksPerLaunch = (1 << 30) / kBlockVoxelCount;  // element indices are ints
        for (int first = 0; first < count; first += kBlocksPerLaunch)
            TDevice::parallelFor(std::min(kBlocksPerLaunch, count - first) * kBlockVoxelCount,
                                 ResetVoxelBlocks<TVoxel>{scene.voxelData(), taken + first});
    }

    // Stage 3: the visible list, in entry order.
    void buildVisibleList(VoxelBlockHash& hash, const SceneParams& params, const View& view,
                          const Mat4f& T_world_camera) {
        const BlockProjection projection{rigidInverse(T_world_camera), view.calib.depth, params.voxel_size_m,
                                         kIntegrationNearM, params.view_frustum_max_m + params.mu_m};
        TDevice::parallelFor(hash.entryCount(), UpdateEntryVisibility{hash.state(), projection});
        const int count = TDevice::selectIndices(hash.entryCount(), EntryIsVisible{hash.entryVisibility()},
                                                 hash.visibleEntriesForWriting(), scratch_);
        hash.setVisibleListFor(count, T_world_camera, view.calib.depth);
    }

    DeviceScratch scratch_{kDevice};
    MemoryBlock<float> depth_staging_;
    // Stage 1 and 2, reused across frames.
    MemoryBlock<std::uint64_t> missing_;
    MemoryBlock<int> missing_count_;
    MemoryBlock<int> target_, claim_, excess_wanted_, excess_rank_, block_wanted_, block_rank_;
    MemoryBlock<std::uint8_t> outcome_, needs_excess_;
    MemoryBlock<InsertRoundCounts> counts_;
    MemoryBlock<int> activation_;  // stored entries the depth needs
    // Removal.
    MemoryBlock<std::uint8_t> remove_;
    MemoryBlock<int> freed_blocks_, freed_excess_;
};

// The engine factory both layers instantiate.
template <class TDevice, class TVoxel, class TIndex>
std::unique_ptr<AllocationEngine<TVoxel, TIndex>> makeAllocationEngineOn() {
    if constexpr (std::is_same<TIndex, VoxelBlockHash>::value)
        return std::make_unique<HashAllocationEngine<TDevice, TVoxel>>();
    else
        return std::make_unique<DenseAllocationEngine<TVoxel>>();
}

}  // namespace voxfuse
