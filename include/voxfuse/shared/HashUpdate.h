#pragma once
// Changing the voxel block hash in parallel, one element at a time: inserting a frame's missing blocks
// (allocation stage 2) and removing blocks (block removal). The CPU and CUDA layers run the same
// functions through their launchers (src/engines/AllocationEngine_Impl.h says in which order), so for
// the same frames both devices build the same table, entry for entry.
//
// Insertion runs in rounds over the frame's distinct missing blocks, sorted by block key. In a round
// each block finds where its insertion must go (its insertion target: the first free ordered entry of
// its bucket, or the tail of the bucket's chain); where several blocks share a target, the one with
// the smallest key wins and the others wait for the next round. Winners take voxel blocks (and excess
// entries) from the tops of the free stacks in key order, by rank from an exclusive scan, so the
// table depends on the frame only, never on thread timing. A block fails when a capacity runs out:
// the excess list (hash full) or the voxel block array (blocks full).
//
// Removal runs per bucket: one element unlinks the removed entries of its bucket's chain, then moves
// chain heads into removed ordered entries (the table's invariant), and pushes what it freed onto the
// free stacks at offsets from a scan of the per-bucket counts: the stacks too are independent of timing.

#include <climits>
#include <cstdint>

#include "voxfuse/core/Atomics.h"
#include "voxfuse/core/Math.h"
#include "voxfuse/objects/HashTableTypes.h"
#include "voxfuse/shared/HashAccess.h"

namespace voxfuse {

// ---- Block keys: a block as one 64-bit integer that sorts by (z, y, x) ----

// Stands for every block outside the coordinates an entry can store (it sorts after all real keys).
constexpr std::uint64_t kOutOfRangeBlockKey = ~std::uint64_t(0);

VF_HOST_DEVICE inline std::uint64_t blockKey(Vec3i b) {
    if (!blockIsAddressable(b)) return kOutOfRangeBlockKey;
    return std::uint64_t(b.x + 32768) | (std::uint64_t(b.y + 32768) << 16) | (std::uint64_t(b.z + 32768) << 32);
}
VF_HOST_DEVICE inline Vec3i blockFromKey(std::uint64_t key) {
    return {int(key & 0xffff) - 32768, int((key >> 16) & 0xffff) - 32768, int((key >> 32) & 0xffff) - 32768};
}

// ---- Insertion rounds ----

// What happened to one missing block.
enum InsertOutcome : std::uint8_t { kInsertPending = 0, kInserted, kInsertFailedHashFull, kInsertFailedBlocksFull };

// Totals of a round, accumulated with atomics by InsertGranted (one struct in device memory).
struct InsertRoundCounts {
    int inserted;       // blocks inserted this round
    int excess_used;    // excess entries taken this round
    int failed_hash;    // blocks that failed for lack of an excess entry this round
    int failed_blocks;  // blocks that failed for lack of a voxel block this round
    int pending;        // blocks left for the next round
};

// The per-block arrays of the rounds and the free-stack sizes at the start of the round.
struct InsertRound {
    HashTableState table;
    const std::uint64_t* keys;   // the distinct missing blocks, sorted
    int* target;                 // insertion target per block while it takes part in a round, else -1
    int* claim;                  // per entry: the smallest block index that targets it (INT_MAX = none)
    std::uint8_t* outcome;       // InsertOutcome per block
    std::uint8_t* needs_excess;  // per block: its target is a chain tail (a new excess entry is linked after it)
    int* excess_wanted;          // per block: 1 for a winner that needs an excess entry
    int* excess_rank;            // exclusive scan of excess_wanted
    int* block_wanted;           // per block: 1 for a winner that may take a voxel block
    int* block_rank;             // exclusive scan of block_wanted
    InsertRoundCounts* counts;
    int free_block_count;  // sizes of the free stacks at the start of the round
    int free_excess_count;
};

// Step 1, per pending block: find the insertion target and claim it.
struct ClaimInsertTarget {
    InsertRound r;
    VF_HOST_DEVICE void operator()(int i) const {
        if (r.outcome[i] != kInsertPending) return;
        int target;
        findHashEntry(r.table.view(), blockFromKey(r.keys[i]),
                      target);  // absent: the block was missing and is distinct
        r.target[i] = target;
        const HashEntry& t = r.table.entries[target];
        r.needs_excess[i] = !(target < r.table.ordered_entry_count && t.ptr == kEntryFree);
        atomicMinInt(&r.claim[target], i);
    }
};

// Step 2, per pending block: winners and the excess entries they want. A block fails at once when a
// stack it needs is empty (it would fail in every later round too: nothing is freed while inserting).
struct DecideInsertWinners {
    InsertRound r;
    VF_HOST_DEVICE void operator()(int i) const {
        r.excess_wanted[i] = 0;
        if (r.outcome[i] != kInsertPending) return;
        if (r.needs_excess[i] && r.free_excess_count == 0) {
            r.outcome[i] = kInsertFailedHashFull;
            atomicAddInt(&r.counts->failed_hash, 1);
            return;
        }
        if (r.free_block_count == 0) {
            r.outcome[i] = kInsertFailedBlocksFull;
            atomicAddInt(&r.counts->failed_blocks, 1);
            return;
        }
        r.excess_wanted[i] = r.claim[r.target[i]] == i && r.needs_excess[i] ? 1 : 0;
    }
};

// Step 3, per pending block (after the scan of excess_wanted): winners whose excess entry exists may
// take a voxel block; the others fail as hash full.
struct GrantInsertBlocks {
    InsertRound r;
    VF_HOST_DEVICE void operator()(int i) const {
        r.block_wanted[i] = 0;
        if (r.outcome[i] != kInsertPending || r.claim[r.target[i]] != i) return;
        if (r.excess_wanted[i] && r.excess_rank[i] >= r.free_excess_count) {
            r.outcome[i] = kInsertFailedHashFull;
            atomicAddInt(&r.counts->failed_hash, 1);
            return;
        }
        r.block_wanted[i] = 1;
    }
};

// Step 4, per block (after the scan of block_wanted): winners insert with the voxel block of their rank.
// Every block that took part releases its claim; the losers stay pending for the next round.
struct InsertGrantedBlocks {
    InsertRound r;
    VF_HOST_DEVICE void operator()(int i) const {
        if (r.outcome[i] != kInsertPending) return;
        if (!r.block_wanted[i]) {
            atomicAddInt(&r.counts->pending, 1);
            return;
        }
        if (r.block_rank[i] >= r.free_block_count) {
            r.outcome[i] = kInsertFailedBlocksFull;
            atomicAddInt(&r.counts->failed_blocks, 1);
            return;
        }
        const Vec3i b = blockFromKey(r.keys[i]);
        const Vec3<std::int16_t> pos{std::int16_t(b.x), std::int16_t(b.y), std::int16_t(b.z)};
        const int ptr = r.table.free_blocks[r.free_block_count - 1 - r.block_rank[i]];
        const int target = r.target[i];
        int entry = target;
        if (!r.needs_excess[i]) {
            r.table.entries[target].pos = pos;  // keeps `next`: a bucket's last entry may carry its chain
            r.table.entries[target].ptr = ptr;
        } else {
            const int excess = r.table.free_excess[r.free_excess_count - 1 - r.excess_rank[i]];
            entry = r.table.ordered_entry_count + excess;
            r.table.entries[entry] = HashEntry{pos, kEndOfChain, ptr};
            r.table.entries[target].next = excess;
            atomicAddInt(&r.counts->excess_used, 1);
        }
        r.table.entry_visibility[entry] = kEntrySeenThisFrame;
        r.outcome[i] = kInserted;
        atomicAddInt(&r.counts->inserted, 1);
    }
};

// After step 4, per block: the claims of the round go back to "none" (INT_MAX) for the next one.
struct ReleaseInsertClaims {
    InsertRound r;
    VF_HOST_DEVICE void operator()(int i) const {
        if (r.target[i] < 0) return;
        racingStore(&r.claim[r.target[i]], INT_MAX);
        r.target[i] = -1;
    }
};

// ---- Removal per bucket ----

// The arrays of a removal pass. `remove` marks entries to delete (active blocks without a stored copy).
struct BucketRemoval {
    HashTableState table;
    const std::uint8_t* remove;
    int* freed_blocks;     // per bucket: voxel blocks it frees (counting pass) / offset (removing pass)
    int* freed_excess;     // per bucket: excess entries it frees / offset
    int free_block_count;  // stack sizes before the pass: freed ids go above them
    int free_excess_count;
};

// Counting pass, per bucket: how many voxel blocks and excess entries the bucket will free.
struct CountBucketRemovals {
    BucketRemoval r;
    VF_HOST_DEVICE void operator()(int bucket) const {
        const HashTableState& t = r.table;
        const int first = bucket * t.entries_per_bucket, last = first + t.entries_per_bucket - 1;
        int removed_ordered = 0, removed_chain = 0, kept_chain = 0;
        for (int k = first; k <= last; ++k) removed_ordered += r.remove[k] ? 1 : 0;
        for (int next = t.entries[last].next; next != kEndOfChain;
             next = t.entries[t.ordered_entry_count + next].next) {
            if (r.remove[t.ordered_entry_count + next])
                ++removed_chain;
            else
                ++kept_chain;
        }
        const int moved = removed_ordered < kept_chain ? removed_ordered : kept_chain;  // chain heads moved up
        r.freed_blocks[bucket] = removed_ordered + removed_chain;
        r.freed_excess[bucket] = removed_chain + moved;
    }
};

// Removing pass, per bucket (after exclusive scans turned the counts into offsets).
struct RemoveBucketEntries {
    BucketRemoval r;
    VF_HOST_DEVICE void operator()(int bucket) const {
        const HashTableState& t = r.table;
        const int first = bucket * t.entries_per_bucket, last = first + t.entries_per_bucket - 1;
        int* block_out = t.free_blocks + r.free_block_count + r.freed_blocks[bucket];
        int* excess_out = t.free_excess + r.free_excess_count + r.freed_excess[bucket];
        // 1. Unlink removed chain entries.
        int prev = last;
        for (int next = t.entries[last].next; next != kEndOfChain;) {
            const int index = t.ordered_entry_count + next;
            const HashEntry e = t.entries[index];
            if (r.remove[index]) {
                *block_out++ = e.ptr;
                *excess_out++ = next;
                t.entries[prev].next = e.next;
                t.entries[index] = HashEntry::empty();
                t.entry_visibility[index] = kEntryNotVisible;
                t.stored_slot[index] = kNoStoredCopy;
            } else {
                prev = index;
            }
            next = e.next;
        }
        // 2. Removed ordered entries: the chain head moves in (keeping its visibility), or the entry is freed.
        for (int k = first; k <= last; ++k) {
            if (!r.remove[k]) continue;
            *block_out++ = t.entries[k].ptr;
            const int head = t.entries[last].next;
            if (head == kEndOfChain) {
                t.entries[k].ptr = kEntryFree;  // `next` stays: only the last entry links a chain
                t.entry_visibility[k] = kEntryNotVisible;
                t.stored_slot[k] = kNoStoredCopy;
                continue;
            }
            // The head moves with everything kept per entry (visibility, stored copy).
            const int head_index = t.ordered_entry_count + head;
            const HashEntry moved = t.entries[head_index];
            t.entries[k].pos = moved.pos;
            t.entries[k].ptr = moved.ptr;
            t.entries[last].next = moved.next;
            t.entry_visibility[k] = t.entry_visibility[head_index];
            t.stored_slot[k] = t.stored_slot[head_index];
            t.entries[head_index] = HashEntry::empty();
            t.entry_visibility[head_index] = kEntryNotVisible;
            t.stored_slot[head_index] = kNoStoredCopy;
            *excess_out++ = head;
        }
    }
};

}  // namespace voxfuse
