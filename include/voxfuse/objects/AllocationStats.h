#pragma once
// What the voxel block hash holds and what the last allocation could not do. A full hash table or
// voxel block array never fails silently: the blocks a frame needed and did not get are counted here.

namespace voxfuse {

struct AllocationStats {
    int blocks_allocated = 0;  // voxel blocks in use now (allocated minus removed)
    int block_capacity = 0;    // voxel blocks backed by memory now (grows on demand up to the maximum)
    int visible_blocks = 0;    // blocks in the visible list of the last allocation (what integration updates)

    int blocks_allocated_this_frame = 0;
    // Distinct blocks the last frame's depth needed that are still unallocated after the allocation,
    // because a capacity ran out (or the block lies beyond the coordinates an entry can store).
    int allocation_failures_this_frame = 0;
    int failures_hash_full_this_frame = 0;    // ... of which: bucket and excess list were full
    int failures_blocks_full_this_frame = 0;  // ... of which: the voxel block array was at its maximum
    // The rest (failures minus the two above) lay outside the block coordinates an entry can store (int16).

    // Stage 1's work in the last allocation: keys appended to the missing list (a block more than once
    // where several tiles of pixels need it), and passes over the depth (more than one when the list
    // had to grow, or overflowed its bound). The same distinct blocks on both devices, whatever these say.
    int missing_block_appends_this_frame = 0;
    int stage1_passes_this_frame = 0;

    long long allocation_failures_total = 0;
    long long blocks_removed_total = 0;

    // Swapping (engines/SwappingEngine.h).
    int blocks_stored = 0;                  // blocks with a copy in the global cache
    int blocks_activated_this_frame = 0;    // stored blocks the depth needed, given a voxel block again
    int blocks_swapped_in_this_frame = 0;   // stored copies merged back in
    int blocks_swapped_out_this_frame = 0;  // active blocks moved to the cache
};

}  // namespace voxfuse
