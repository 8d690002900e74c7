#pragma once
// Swapping blocks between the active voxel array and the global cache (section 5 of the InfiniTAM
// report), one element at a time, for the CPU and CUDA layers alike (engines/SwappingEngine.h says in
// which order). Entry states: HashTableTypes.h (active, stored, merge pending).

#include <cstdint>

#include "voxfuse/core/Math.h"
#include "voxfuse/objects/HashTableTypes.h"
#include "voxfuse/shared/Allocation.h"  // blockIsEmpty
#include "voxfuse/shared/BlockProjection.h"

namespace voxfuse {

// The InfiniTAM report's secondary integration: a block that came back into the voxel array while its stored
// copy was still in the cache has fused new frames since; the stored copy is merged in as one more
// weighted observation, never overwriting. With nothing fused since (active weight 0) the stored
// voxel comes back exactly, so a block swapped out and in again is bit-identical.
template <class TVoxel>
VF_HOST_DEVICE inline void mergeStoredVoxel(TVoxel& active, const TVoxel& stored, int max_weight) {
    const int wa = active.w_depth, ws = stored.w_depth;
    if (wa == 0) {  // colour and class are fused only with depth: they have no weight either
        active = stored;
        return;
    }
    if (ws > 0) {
        const float fused =
            (TVoxel::sdfToFloat(active.sdf) * float(wa) + TVoxel::sdfToFloat(stored.sdf) * float(ws)) / float(wa + ws);
        active.sdf = TVoxel::sdfFromFloat(fused);
        active.w_depth = (unsigned char)(wa + ws < max_weight ? wa + ws : max_weight);
    }
    if constexpr (TVoxel::hasColor) {
        const int ca = active.w_color, cs = stored.w_color;
        if (cs > 0 && ca == 0) {
            active.clr = stored.clr;
            active.w_color = stored.w_color;
        } else if (cs > 0) {
            auto blend = [ca, cs](unsigned char a, unsigned char s) {
                return (unsigned char)((float(a) * float(ca) + float(s) * float(cs)) / float(ca + cs) + 0.5f);
            };
            active.clr = Vec3u8{blend(active.clr.x, stored.clr.x), blend(active.clr.y, stored.clr.y),
                                blend(active.clr.z, stored.clr.z)};
            active.w_color = (unsigned char)(ca + cs < max_weight ? ca + cs : max_weight);
        }
    }
    if constexpr (TVoxel::hasLabel) {
        // Two counts of classes merge as a majority vote: the same class adds up, different ones cancel.
        const int la = active.w_label, ls = stored.w_label;
        if (ls > 0 && la == 0) {
            active.label = stored.label;
            active.w_label = stored.w_label;
        } else if (ls > 0 && stored.label == active.label) {
            active.w_label = (unsigned char)(la + ls < max_weight ? la + ls : max_weight);
        } else if (ls > 0) {
            if (ls > la) active.label = stored.label;
            const int rest = ls > la ? ls - la : la - ls;
            active.w_label = (unsigned char)(rest > 0 ? rest : 1);
        }
    }
}

// The room the voxel array keeps for the view: blocks in the raycast's reach but out of the view stay in
// it, or come back to it, only beyond this many free blocks. The next frame's view needs about as many
// blocks as this frame's.
inline int reachReserveBlocks(int visible_blocks) { return visible_blocks; }

// ---- Selections (for the launchers' selectIndices) ----

// Stored blocks this frame needs, in two passes: first those allocation stage 1 saw in the depth (they
// fuse it), then (reach_only) the others the raycast from this viewpoint can read (RaycastReach).
struct EntryNeedsActivation {
    const HashEntry* entries;
    const std::uint8_t* entry_visibility;
    RaycastReach reach;
    bool reach_only;
    VF_HOST_DEVICE bool operator()(int i) const {
        const HashEntry& e = entries[i];
        if (e.ptr != kEntrySwappedOut) return false;
        if (entry_visibility[i] == kEntrySeenThisFrame) return !reach_only;
        return reach_only && reach.contains({e.pos.x, e.pos.y, e.pos.z});
    }
};

// Blocks back in the voxel array whose stored copy waits to be merged in, in the visible list (they fuse
// this frame: their copies come first) or (!visible) not. The slot (4 bytes an entry) is tested first: a
// pass over every entry then reads a 16-byte entry only for stored blocks.
struct EntryMergePending {
    const HashEntry* entries;
    const int* stored_slot;
    const std::uint8_t* entry_visibility;
    bool visible;
    VF_HOST_DEVICE bool operator()(int i) const {
        return stored_slot[i] != kNoStoredCopy && entries[i].ptr >= 0 &&
               (entry_visibility[i] == kEntryVisible) == visible;
    }
};

// Active blocks out of the view (not in the visible list) with nothing waiting to be merged, out of the
// raycast's reach or (in_reach) in it. Empty blocks stay: block removal frees them, as it would without
// swapping.
template <class TVoxel>
struct EntryCanSwapOut {
    const HashEntry* entries;
    const std::uint8_t* entry_visibility;
    const int* stored_slot;
    const TVoxel* voxels;
    RaycastReach reach;
    bool in_reach;
    VF_HOST_DEVICE bool operator()(int i) const {
        const HashEntry& e = entries[i];
        return e.ptr >= 0 && entry_visibility[i] != kEntryVisible && stored_slot[i] == kNoStoredCopy &&
               reach.contains({e.pos.x, e.pos.y, e.pos.z}) == in_reach &&
               !blockIsEmpty(voxels + (long long)e.ptr * kBlockVoxelCount);
    }
};

// ---- Loop bodies ----

// Allocation, per listed entry k (EntryNeedsActivation): the voxel block of rank k from the top of the
// free stack (`free_block_count` high), for the first `granted` (at most free_block_count); the stored
// copy stays, to be merged in. The entries beyond stay stored and out of this frame's view.
struct ActivateStoredBlocks {
    HashTableState table;
    const int* listed;
    int free_block_count;
    int granted;
    VF_HOST_DEVICE void operator()(int k) const {
        const int entry = listed[k];
        if (k < granted)
            table.entries[entry].ptr = table.free_blocks[free_block_count - 1 - k];
        else
            table.entry_visibility[entry] = kEntryNotVisible;
    }
};

// Swapping in, per listed entry k (EntryMergePending): its cache slot, for the host to read.
struct GatherStoredSlots {
    const int* listed;
    const int* stored_slot;
    int* slots;
    VF_HOST_DEVICE void operator()(int k) const { slots[k] = stored_slot[listed[k]]; }
};

// Swapping in, element i: voxel i % 512 of listed block i / 512 takes in its stored copy from the
// transfer buffer (block k at transfer[k * 512]).
template <class TVoxel>
struct MergeStoredBlocks {
    TVoxel* voxels;
    const HashEntry* entries;
    const int* listed;
    const TVoxel* transfer;
    int max_weight;
    VF_HOST_DEVICE void operator()(int i) const {
        const int k = i / kBlockVoxelCount, v = i % kBlockVoxelCount;
        mergeStoredVoxel(voxels[(long long)entries[listed[k]].ptr * kBlockVoxelCount + v],
                         transfer[(long long)k * kBlockVoxelCount + v], max_weight);
    }
};

// Swapping in, per listed entry k, once merged: nothing waits any more.
struct ClearStoredSlots {
    const int* listed;
    int* stored_slot;
    VF_HOST_DEVICE void operator()(int k) const { stored_slot[listed[k]] = kNoStoredCopy; }
};

// Swapping out, element i: voxel i % 512 of listed block i / 512 into the transfer buffer.
template <class TVoxel>
struct GatherBlockVoxels {
    const TVoxel* voxels;
    const HashEntry* entries;
    const int* listed;
    TVoxel* transfer;
    VF_HOST_DEVICE void operator()(int i) const {
        const int k = i / kBlockVoxelCount, v = i % kBlockVoxelCount;
        transfer[(long long)k * kBlockVoxelCount + v] =
            voxels[(long long)entries[listed[k]].ptr * kBlockVoxelCount + v];
    }
};

// Swapping out, per listed entry k, once its voxels are in the cache at slots[k]: the entry becomes
// stored and its voxel block goes onto the free stack (above its `free_block_count` entries, in order).
struct MarkSwappedOut {
    HashTableState table;
    const int* listed;
    const int* slots;
    int free_block_count;
    VF_HOST_DEVICE void operator()(int k) const {
        const int entry = listed[k];
        table.free_blocks[free_block_count + k] = table.entries[entry].ptr;
        table.entries[entry].ptr = kEntrySwappedOut;
        table.stored_slot[entry] = slots[k];
        table.entry_visibility[entry] = kEntryNotVisible;
    }
};

}  // namespace voxfuse
