#pragma once
// The sparse index (section 3.3 of the InfiniTAM report): voxels live in 8x8x8 blocks that exist only
// near observed surfaces. A hash of the block coordinates picks a bucket of the ordered table; when the
// bucket is full, further blocks of that bucket are chained through an unordered excess list. Blocks
// and excess entries come from free stacks. The voxel block array grows on demand, so memory follows
// the scene rather than a fixed box. Entry layout and the views loop bodies use: HashTableTypes.h.
//
// The tables live on one device, the scene's (location()): a hash on the GPU keeps no host copy. The
// sizes of the free stacks and the visible list are host-side numbers. The host-side table operations
// (findEntry, insert, removeBlocks, entry) serve tests and tools on a hash in host memory; the engines
// change the tables through their device layers (engines/AllocationEngine.h).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/core/Math.h"
#include "voxfuse/core/MemoryBlock.h"
#include "voxfuse/objects/AllocationStats.h"
#include "voxfuse/objects/HashTableTypes.h"
#include "voxfuse/objects/Intrinsics.h"

namespace voxfuse {

template <class TVoxel, class TIndex>
class Scene;

class VoxelBlockHash {
public:
    static constexpr const char* name = "hash";
    using Settings = VoxelBlockHashSettings;
    // What device-agnostic code needs to find a block (trivially copyable).
    using Data = HashTableView;

    enum class InsertResult { Inserted, AlreadyPresent, NoHashEntry, NoVoxelBlock, OutOfRange };

    // An empty table on `location`. Throws ConfigError on sizes out of range.
    explicit VoxelBlockHash(const Settings& settings = Settings(), Device location = Device::CPU);
    VoxelBlockHash(VoxelBlockHash&&) = default;
    VoxelBlockHash& operator=(VoxelBlockHash&&) = default;

    const Settings& settings() const { return settings_; }
    Device location() const { return location_; }
    // Moves the tables to `where`, contents kept (a Scene moves its index to its own device).
    void moveTo(Device where);
    // An independent copy of the whole index on `where`, e.g. a host snapshot of a map on the GPU.
    VoxelBlockHash copyTo(Device where) const;

    // The tables on location(): lookups read Data; the engines' device layers change the State.
    Data data() const;
    HashTableState state();
    int entryCount() const { return int(entries_.size()); }

    int blockCapacity() const { return block_capacity_; }  // blocks backed by voxel memory
    int blocksInUse() const { return block_capacity_ - free_block_count_; }
    int freeBlocks() const { return free_block_count_; }  // within the current capacity
    int freeExcessEntries() const { return free_excess_count_; }
    bool canGrow() const { return block_capacity_ < settings_.max_block_count; }
    // Voxels the scene must store: blockCapacity() blocks of 512.
    std::size_t voxelCount() const { return voxelCountFor(block_capacity_); }
    static std::size_t voxelCountFor(int blocks) { return std::size_t(blocks) * kBlockVoxelCount; }
    // Voxels it may come to store: settings().max_block_count blocks of 512.
    std::size_t maxVoxelCount() const { return std::size_t(settings_.max_block_count) * kBlockVoxelCount; }
    // Memory of the index itself (entry table, free stacks, visibility, visible list); fixed by the settings.
    // The same, from the settings alone: what constructing the index will allocate.
    static std::size_t tableBytesFor(const Settings& settings);
    // The settings of a table once it has grown all it may (growBuckets up to max_bucket_count).
    static Settings fullyGrown(const Settings& settings);
    std::size_t tableBytes() const {
        return entries_.bytes() + free_blocks_.bytes() + free_excess_.bytes() + entry_visibility_.bytes() +
               stored_slot_.bytes() + visible_entries_.bytes();
    }
    // Whether the table, with `adding` more blocks, would hold more than kMaxBucketLoad of its ordered
    // entries, and may still grow (settings().max_bucket_count).
    bool wantsMoreBuckets(int adding = 0) const;
    // Doubles the buckets and the excess list, once and then until `adding` more blocks would not take
    // the table past kMaxBucketLoad (at most to max_bucket_count), and moves every entry into the new
    // table in entry order: the blocks keep their voxel blocks, stored slots and visibility, the visible
    // list its blocks (in the new entry order). On the GPU through host memory, once per call. Entry
    // indices change: nothing may keep one across this call.
    void growBuckets(int adding = 0);
    // After a device layer took blocks and excess entries from the tops of the free stacks (negative:
    // pushed back), keeps the stack sizes and the statistics in step.
    void popFreeStacks(int blocks, int excess_entries);
    // Blocks with a copy in the global cache (stored, or merge pending): kept by the swapping engine.
    int storedBlocks() const { return stored_block_count_; }
    void addStoredBlocks(int count) { stored_block_count_ += count; }

    // ---- Host-side table operations (serial; a hash on the GPU throws DeviceError) ----
    const HashEntry& entry(int i) const;
    // Entry index holding `block` (ptr >= 0 or swapped out), or -1.
    int findEntry(Vec3i block) const;
    // Inserts `block` with a voxel block from the free stack; `entry_out` receives its entry. The block's
    // voxels are whatever the array holds: the caller resets them (the allocation engine does).
    InsertResult insert(Vec3i block, int* entry_out = nullptr);
    // Inserts `block` as stored in the global cache at `slot` (no voxel block; reading a map that is
    // larger than the voxel array).
    InsertResult insertStored(Vec3i block, int slot, int* entry_out = nullptr);
    // Removes the given blocks (absent ones are skipped) with the removal of shared/HashUpdate.h: voxel
    // blocks and excess entries go back to their free stacks, chains stay linked, and the visible list
    // keeps the blocks that remain. Returns how many were removed.
    int removeBlocks(const std::vector<Vec3i>& blocks);

    // ---- The visible list of the live view (written by allocation stage 3, read by integration and raycast) ----
    // Entry indices on location().
    const int* visibleEntries() const { return visible_entries_.data(location_); }
    int* visibleEntriesForWriting() { return visible_entries_.data(location_); }
    int visibleCount() const { return visible_count_; }
    // Per entry: kEntryVisible for the entries of the visible list (kept between frames), on location().
    const std::uint8_t* entryVisibility() const { return entry_visibility_.data(location_); }
    // Per entry: the global cache slot of its stored copy or kNoStoredCopy, on location().
    const int* storedSlots() const { return stored_slot_.data(location_); }
    // Host-side: makes `entries` the visible list (tests and tools; a hash on the GPU throws DeviceError).
    void setVisibleEntries(const std::vector<int>& entries, const Mat4f& T_world_camera, const Intrinsics& intrinsics);
    // After a device layer wrote `count` entries to visibleEntriesForWriting() and their visibility:
    // for a new view, or (block removal) for the view the list was built for.
    void setVisibleListFor(int count, const Mat4f& T_world_camera, const Intrinsics& intrinsics);
    void setVisibleCount(int count);
    // True when the visible list was built for this viewpoint and a camera that sees all this one does:
    // the same intrinsics, or these are the list's downsampled by an integer factor (the tracking
    // raycast at half resolution), whose frustum lies inside the list's.
    bool visibleListCovers(const Mat4f& T_world_camera, const Intrinsics& intrinsics) const;
    // The viewpoint the visible list was built for; false before the first list.
    bool visibleListViewpoint(Mat4f& T_world_camera, Intrinsics& intrinsics) const {
        T_world_camera = visible_T_world_camera_;
        intrinsics = visible_intrinsics_;
        return visible_valid_;
    }

    AllocationStats& stats() { return stats_; }
    const AllocationStats& stats() const { return stats_; }

private:
    // Growth changes how many voxels the scene stores, so only Scene calls these (it reallocates the voxels).
    template <class, class>
    friend class Scene;
    // The capacity a growth to at least `blocks` would give (capped at the maximum; in steps of
    // blocks_per_growth, or a quarter more): blockCapacity() when it cannot or need not grow.
    int grownBlockCapacity(int blocks) const;
    // Raises the capacity to `capacity` (from grownBlockCapacity), once the voxels for it exist: a
    // failed voxel allocation must not leave the free stack handing out blocks past the array's end.
    void setBlockCapacity(int capacity);
    // Empties the table and returns the capacity to zero.
    void clearBlocks();

    void requireHost(const char* what) const;
    // The host-side numbers (block counts, the visible list's size and viewpoint, statistics) but the
    // excess stack's size, which follows the table.
    void copyBookkeepingTo(VoxelBlockHash& to) const;
    VoxelBlockHash(const Settings& settings, Device location, bool allocate_tables);

    Settings settings_;
    Device location_;
    MemoryBlock<HashEntry> entries_;
    MemoryBlock<int> free_blocks_;  // stack of free voxel block indices below block_capacity_
    MemoryBlock<int> free_excess_;  // stack of free excess-list indices
    MemoryBlock<std::uint8_t> entry_visibility_;
    MemoryBlock<int> stored_slot_;  // per entry, see HashTableState
    int free_block_count_ = 0;
    int free_excess_count_ = 0;
    int block_capacity_ = 0;
    int stored_block_count_ = 0;
    // Insertion into `target` (findHashEntry's) of a new entry with this ptr; false when the excess list is full.
    bool insertEntry(int target, Vec3i block, int ptr, int* entry_out);

    MemoryBlock<int> visible_entries_;
    int visible_count_ = 0;
    bool visible_valid_ = false;
    Mat4f visible_T_world_camera_ = Mat4f::identity();
    Intrinsics visible_intrinsics_;

    AllocationStats stats_;
};

}  // namespace voxfuse
