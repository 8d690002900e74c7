#pragma once
// The sparse index (section 3.3 of the InfiniTAM report): voxels live in 8x8x8 blocks that exist only
// near observed surfaces. A hash of the block coordinates picks a bucket of the ordered table; when the
// bucket is full, further blocks of that bucket are chained through an unordered excess list. Blocks
// and excess entries come from free stacks. The voxel block array grows on demand, so memory follows
// the scene rather than a fixed box.
//
// Layout of the entry table: bucket_count * entries_per_bucket ordered entries, then excess_entry_count
// excess entries. A bucket's chain starts at the `next` of its last ordered entry. Invariant: a bucket
// has a chain only while all its ordered entries are occupied (insertion fills the bucket first;
// removal moves the chain head into a freed ordered entry).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "voxfuse/core/Math.h"
#include "voxfuse/core/MemoryBlock.h"
#include "voxfuse/objects/AllocationStats.h"
#include "voxfuse/objects/Intrinsics.h"

namespace voxfuse {

template <class TVoxel, class TIndex>
class Scene;

constexpr int kBlockSide = 8;                                          // voxels along each edge of a block
constexpr int kBlockVoxelCount = kBlockSide * kBlockSide * kBlockSide;  // 512, stored x-fastest

// HashEntry::ptr values that are not a voxel block.
constexpr int kEntryFree = -1;        // the entry holds no block
constexpr int kEntrySwappedOut = -2;  // reserved for swapping: the block exists but is not in the voxel array
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

// Sizes of the hash index. Defaults are those of DESIGN.md.
struct VoxelBlockHashSettings {
    int bucket_count = 0x100000;       // buckets of the ordered table (any positive number; powers of two hash faster)
    int entries_per_bucket = 1;        // ordered entries per bucket: 1 or 2 (the report's buckets hold 2)
    int excess_entry_count = 0x20000;  // entries of the excess list shared by all buckets
    int max_block_count = 1 << 18;     // voxel blocks the array may grow to (2^18 x 512 voxels), at most 2^22
    // The voxel block array starts empty and grows by max(blocks_per_growth, a quarter of its size),
    // so a small scene costs little and growth copies each voxel about four times in all.
    int blocks_per_growth = 4096;      // 4096 blocks = 2M voxels
};

class VoxelBlockHash {
public:
    static constexpr const char* name = "hash";
    using Settings = VoxelBlockHashSettings;

    // What device-agnostic code needs to find a block (trivially copyable).
    struct Data {
        const HashEntry* entries;  // ordered entries, then the excess list
        int bucket_count;
        int entries_per_bucket;
        int ordered_entry_count;   // bucket_count * entries_per_bucket: excess entry i is entries[ordered_entry_count + i]
        int excess_entry_count;
    };

    enum class InsertResult { Inserted, AlreadyPresent, NoHashEntry, NoVoxelBlock, OutOfRange };

    // Throws ConfigError on sizes out of range.
    explicit VoxelBlockHash(const Settings& settings = Settings());

    const Settings& settings() const { return settings_; }
    Data data() const;
    int entryCount() const { return int(entries_.size()); }
    const HashEntry& entry(int i) const { return entries_.host()[i]; }

    int blockCapacity() const { return block_capacity_; }                 // blocks backed by voxel memory
    int blocksInUse() const { return block_capacity_ - free_block_count_; }
    int freeBlocks() const { return free_block_count_; }                  // within the current capacity
    int freeExcessEntries() const { return free_excess_count_; }
    bool canGrow() const { return block_capacity_ < settings_.max_block_count; }
    // Voxels the scene must store: blockCapacity() blocks of 512.
    std::size_t voxelCount() const { return std::size_t(block_capacity_) * kBlockVoxelCount; }
    // Memory of the index itself (entry table, free stacks, visible list); fixed by the settings.
    std::size_t tableBytes() const { return entries_.bytes() + free_blocks_.bytes() + free_excess_.bytes() + visible_entries_.bytes(); }

    // ---- Host-side table operations (serial) ----
    // Entry index holding `block` (ptr >= 0 or swapped out), or -1.
    int findEntry(Vec3i block) const;
    // Inserts `block` with a voxel block from the free stack; `entry_out` receives its entry. The block's
    // voxels are whatever the array holds: the caller resets them (the allocation engine does).
    InsertResult insert(Vec3i block, int* entry_out = nullptr);
    // Inserts `block` at `target`, the entry findEntryOrInsertTarget() chose for it (allocation stage 2):
    // into `target` when it is a free ordered entry, else into a new excess entry chained after it.
    InsertResult insertAt(int target, Vec3i block, int* entry_out = nullptr);
    // Removes the given blocks (absent ones are skipped): voxel blocks and excess entries go back to their
    // free stacks, chains stay linked and the visible list stays valid. Returns how many were removed.
    int removeBlocks(const std::vector<Vec3i>& blocks);

    // ---- The visible list of the live view (written by allocation stage 3, read by integration and raycast) ----
    const int* visibleEntries() const { return visible_entries_.host(); }
    int visibleCount() const { return visible_count_; }
    void setVisibleEntries(const std::vector<int>& entries, const Mat4f& T_world_camera, const Intrinsics& intrinsics);
    // True when the visible list was built for exactly this viewpoint and camera.
    bool visibleListIsFor(const Mat4f& T_world_camera, const Intrinsics& intrinsics) const;

    AllocationStats& stats() { return stats_; }
    const AllocationStats& stats() const { return stats_; }

private:
    // Growth changes how many voxels the scene stores, so only Scene calls these (it reallocates the voxels).
    template <class, class>
    friend class Scene;
    // Raises the capacity to at least `blocks` (capped at the maximum). True when it changed.
    bool growBlockCapacity(int blocks);
    // Empties the table and returns the capacity to zero.
    void clearBlocks();

    void removeEntry(int index);  // unlinks one entry (see the invariant above)
    int popFreeBlock();
    int popFreeExcessEntry();

    Settings settings_;
    MemoryBlock<HashEntry> entries_;
    MemoryBlock<int> free_blocks_;  // stack of free voxel block indices below block_capacity_
    MemoryBlock<int> free_excess_;  // stack of free excess-list indices
    int free_block_count_ = 0;
    int free_excess_count_ = 0;
    int block_capacity_ = 0;

    MemoryBlock<int> visible_entries_;
    int visible_count_ = 0;
    bool visible_valid_ = false;
    Mat4f visible_T_world_camera_ = Mat4f::identity();
    Intrinsics visible_intrinsics_;

    AllocationStats stats_;
};

}  // namespace voxfuse
