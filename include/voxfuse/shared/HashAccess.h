#pragma once
// Finding voxels through the voxel block hash, one element at a time (CPU loops and CUDA kernels alike).

#include "voxfuse/core/Math.h"
#include "voxfuse/objects/HashTableTypes.h"

namespace voxfuse {

// The block holding voxel p and p's offset inside it (x-fastest). Arithmetic shifts round down for
// negative coordinates too (g++, clang and nvcc all shift signed values arithmetically).
VF_HOST_DEVICE inline Vec3i blockOfVoxel(Vec3i p) { return {p.x >> 3, p.y >> 3, p.z >> 3}; }
VF_HOST_DEVICE inline int voxelIndexInBlock(Vec3i p) { return (p.x & 7) + (p.y & 7) * 8 + (p.z & 7) * 64; }

// The InfiniTAM report's hash: ((x * 73856093) ^ (y * 19349669) ^ (z * 83492791)) mod bucket_count, in unsigned
// arithmetic (signed overflow would be undefined); a mask when bucket_count is a power of two.
VF_HOST_DEVICE inline int hashBucket(Vec3i block, int bucket_count) {
    const unsigned h =
        (unsigned(block.x) * 73856093u) ^ (unsigned(block.y) * 19349669u) ^ (unsigned(block.z) * 83492791u);
    const unsigned n = unsigned(bucket_count);
    return int((n & (n - 1u)) == 0u ? (h & (n - 1u)) : (h % n));
}

// Whether an entry can store these block coordinates (int16).
VF_HOST_DEVICE inline bool blockIsAddressable(Vec3i block) {
    return block.x >= -kMaxBlockCoordinate && block.x <= kMaxBlockCoordinate && block.y >= -kMaxBlockCoordinate &&
           block.y <= kMaxBlockCoordinate && block.z >= -kMaxBlockCoordinate && block.z <= kMaxBlockCoordinate;
}

VF_HOST_DEVICE inline bool entryHolds(const HashEntry& e, Vec3i block) {
    return e.ptr != kEntryFree && e.pos.x == block.x && e.pos.y == block.y && e.pos.z == block.z;
}

// Entry index of `block` (allocated or swapped out), or -1. Also reports where an insertion of an absent
// block must go: the first free ordered entry of its bucket, or else the last entry of the bucket's chain
// (a new excess entry is linked after it).
VF_HOST_DEVICE inline int findHashEntry(const HashTableView& h, Vec3i block, int& insert_target) {
    const int first = hashBucket(block, h.bucket_count) * h.entries_per_bucket;
    insert_target = -1;
    for (int k = 0; k < h.entries_per_bucket; ++k) {
        const HashEntry& e = h.entries[first + k];
        if (entryHolds(e, block)) return first + k;
        if (e.ptr == kEntryFree && insert_target < 0) insert_target = first + k;
    }
    int tail = first + h.entries_per_bucket - 1;
    for (int next = h.entries[tail].next; next != kEndOfChain;) {
        const int i = h.ordered_entry_count + next;
        if (entryHolds(h.entries[i], block)) return i;
        tail = i;
        next = h.entries[i].next;
    }
    if (insert_target < 0) insert_target = tail;
    return -1;
}

VF_HOST_DEVICE inline int findHashEntry(const HashTableView& h, Vec3i block) {
    int unused;
    return findHashEntry(h, block, unused);
}

// Voxel block index of `block`, or -1 when it has none in the voxel array.
VF_HOST_DEVICE inline int findVoxelBlock(const HashTableView& h, Vec3i block) {
    if (!blockIsAddressable(block)) return -1;
    const int e = findHashEntry(h, block);
    return e >= 0 && h.entries[e].ptr >= 0 ? h.entries[e].ptr : -1;
}

// `found` is false where no block is allocated (the returned voxel is then TVoxel::initial()).
template <class TVoxel>
VF_HOST_DEVICE inline TVoxel readVoxel(const TVoxel* voxels, const HashTableView& h, Vec3i p, bool& found) {
    const int ptr = findVoxelBlock(h, blockOfVoxel(p));
    found = ptr >= 0;
    return found ? voxels[ptr * kBlockVoxelCount + voxelIndexInBlock(p)] : TVoxel::initial();
}

// A hash view that remembers the last block it looked up: the neighbouring reads of an interpolation or
// of consecutive ray steps mostly fall in one block. One per thread (or ray); the table must not change
// while it is in use. Works with every reader of shared/VoxelAccess.h.
struct CachedHashView {
    HashTableView hash;
    mutable Vec3i last_block;
    mutable int last_ptr;

    VF_HOST_DEVICE explicit CachedHashView(const HashTableView& h)
        : hash(h), last_block{-0x7fffffff, 0, 0}, last_ptr(-1) {}  // no voxel lies in block x = -2^31 + 1
    // A view of no table, for arrays of views assigned before use.
    VF_HOST_DEVICE CachedHashView() : CachedHashView(HashTableView{nullptr, 0, 0, 0, 0}) {}

    VF_HOST_DEVICE int voxelBlock(Vec3i block) const {
        if (block != last_block) {
            last_block = block;
            last_ptr = findVoxelBlock(hash, block);
        }
        return last_ptr;
    }
};

template <class TVoxel>
VF_HOST_DEVICE inline TVoxel readVoxel(const TVoxel* voxels, const CachedHashView& view, Vec3i p, bool& found) {
    const int ptr = view.voxelBlock(blockOfVoxel(p));
    found = ptr >= 0;
    return found ? voxels[ptr * kBlockVoxelCount + voxelIndexInBlock(p)] : TVoxel::initial();
}

}  // namespace voxfuse
