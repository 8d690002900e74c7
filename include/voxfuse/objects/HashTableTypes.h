#pragma once
// The voxel block hash as device code sees it: entry layout, constants, settings and the views of the
// tables that loop bodies take (section 3.3 of the InfiniTAM report). Plain data only: no <vector>,
// no exceptions, trivially copyable, so that CUDA kernels include it as they are. The owning class
// with its host-side operations is VoxelBlockHash.
//
// Layout of the entry table: bucket_count * entries_per_bucket ordered entries, then excess_entry_count
// excess entries. A bucket's chain starts at the `next` of its last ordered entry. Invariant: a bucket
// has a chain only while all its ordered entries are occupied (insertion fills the bucket first;
// removal moves the chain head into a freed ordered entry).

#include <cstdint>

#include "voxfuse/core/Math.h"

namespace voxfuse {

constexpr int kBlockSide = 8;                                           // voxels along each edge of a block
constexpr int kBlockVoxelCount = kBlockSide * kBlockSide * kBlockSide;  // 512, stored x-fastest

// HashEntry::ptr values that are not a voxel block.
constexpr int kEntryFree = -1;        // the entry holds no block
constexpr int kEntrySwappedOut = -2;  // the block exists, stored in the global cache only (not in the voxel array)
// HashTableState::stored_slot of an entry whose block has no copy in the global cache.
constexpr int kNoStoredCopy = -1;
// HashEntry::next at the end of a chain.
constexpr int kEndOfChain = -1;

// Block coordinates are stored as int16: blocks beyond +-32767 (1.3 km at 5 mm voxels) cannot be held.
constexpr int kMaxBlockCoordinate = 32767;

struct HashEntry {
    Vec3<std::int16_t> pos;  // block coordinates (voxel coordinates divided by 8, rounded down)
    int next;                // excess-list index of the next entry of this bucket's chain, or kEndOfChain
    int ptr;                 // voxel block index (>= 0), kEntryFree or kEntrySwappedOut

    VF_HOST_DEVICE static HashEntry empty() { return {{0, 0, 0}, kEndOfChain, kEntryFree}; }
};
static_assert(sizeof(HashEntry) == 16, "hash entries are 16 bytes (one aligned load on a GPU)");

// Per-entry visibility, kept by the hash between frames (VoxelBlockHash::entryVisibility()).
constexpr std::uint8_t kEntryNotVisible = 0;
constexpr std::uint8_t kEntrySeenThisFrame = 1;  // allocation stage 1 or 2 found the block in the depth
constexpr std::uint8_t kEntryVisible = 2;        // in the visible list of the last allocation

// MainEngineSettings::hash.max_block_count: the engine chooses the ceiling for its device and memory.
constexpr int kAutomaticBlockCount = 0;

// Sizes of the hash index. The table's defaults are InfiniTAM's.
struct VoxelBlockHashSettings {
    int bucket_count = 0x100000;       // buckets of the ordered table (any positive number; powers of two hash faster)
    int entries_per_bucket = 1;        // ordered entries per bucket: 1 or 2 (the InfiniTAM report's buckets hold 2)
    int excess_entry_count = 0x20000;  // entries of the excess list shared by all buckets
    // The table doubles (its excess list with it) before an allocation would fill more than
    // kMaxBucketLoad of its entries, up to this many buckets; at most bucket_count: a fixed table. So a
    // small scene scans and keeps a small table, and a large one ends with the table it needs.
    int max_bucket_count = 0;
    // Voxel blocks the array may grow to (2^18 x 512 voxels), at most 2^22. MainEngineSettings starts
    // from kAutomaticBlockCount instead: the engine then chooses (automaticMaxBlockCount in MainEngine.h).
    int max_block_count = 1 << 18;
    // The voxel block array starts empty and grows by max(blocks_per_growth, a quarter of its size),
    // so a small scene costs little and growth copies each voxel about four times in all.
    int blocks_per_growth = 4096;  // 4096 blocks = 2M voxels
};

// A growable table doubles rather than hold more blocks than this share of its ordered entries: with
// one entry per bucket about 0.33 of the buckets are then taken and 0.07 of them chain into the excess
// list, which holds an eighth (the share of InfiniTAM's tables).
constexpr float kMaxBucketLoad = 0.4f;

// What a lookup needs (read-only), on the device where the tables live.
struct HashTableView {
    const HashEntry* entries;  // ordered entries, then the excess list
    int bucket_count;
    int entries_per_bucket;
    int ordered_entry_count;  // bucket_count * entries_per_bucket: excess entry i is entries[ordered_entry_count + i]
    int excess_entry_count;
};

// What the device layers of allocation, removal and swapping change: the tables themselves, on their
// device. The free stacks are popped from the top: the next free voxel block is
// free_blocks[free_block_count - 1] (the counts are kept by VoxelBlockHash on the host).
// With swapping (engines/SwappingEngine.h) an entry's block is in one of three states:
//   active         ptr >= 0, stored_slot == kNoStoredCopy: in the voxel array only;
//   stored         ptr == kEntrySwappedOut, stored_slot >= 0: in the global cache only;
//   merge pending  ptr >= 0, stored_slot >= 0: back in the voxel array (fusing new frames) while its
//                  stored copy waits to be merged in.
struct HashTableState {
    HashEntry* entries;
    int* free_blocks;                // stack of free voxel block indices below the block capacity
    int* free_excess;                // stack of free excess-list indices
    std::uint8_t* entry_visibility;  // one of kEntryNotVisible / kEntrySeenThisFrame / kEntryVisible per entry
    int* stored_slot;                // per entry: the global cache slot of its stored copy, or kNoStoredCopy
    int entry_count;
    int bucket_count;
    int entries_per_bucket;
    int ordered_entry_count;
    int excess_entry_count;

    VF_HOST_DEVICE HashTableView view() const {
        return {entries, bucket_count, entries_per_bucket, ordered_entry_count, excess_entry_count};
    }
};

}  // namespace voxfuse
