// Host-side operations of the voxel block hash: construction, insertion, removal, growth.

#include "voxfuse/objects/VoxelBlockHash.h"

#include <algorithm>
#include <climits>
#include <cstring>
#include <string>

#include "voxfuse/core/Error.h"
#include "voxfuse/shared/HashAccess.h"

namespace voxfuse {
namespace {

void validate(const VoxelBlockHashSettings& s) {
    auto fail = [](const std::string& what) { throw ConfigError("voxel block hash: " + what); };
    if (s.bucket_count < 1) fail("bucket count must be positive (got " + std::to_string(s.bucket_count) + ")");
    if (s.entries_per_bucket != 1 && s.entries_per_bucket != 2)
        fail("entries per bucket must be 1 or 2 (got " + std::to_string(s.entries_per_bucket) + ")");
    if (s.excess_entry_count < 0) fail("excess list size must not be negative (got " + std::to_string(s.excess_entry_count) + ")");
    if ((long long)s.bucket_count * s.entries_per_bucket + s.excess_entry_count > INT_MAX) fail("too many hash entries");
    // Voxel offsets ptr * 512 + i are ints: 2^22 blocks (2^31 voxels) at most.
    if (s.max_block_count < 1 || s.max_block_count > (1 << 22))
        fail("maximum block count must be in 1..4194304 (got " + std::to_string(s.max_block_count) + ")");
    if (s.blocks_per_growth < 1) fail("blocks per growth must be positive (got " + std::to_string(s.blocks_per_growth) + ")");
}

Vec3<std::int16_t> toEntryPos(Vec3i block) { return {std::int16_t(block.x), std::int16_t(block.y), std::int16_t(block.z)}; }

Vec3i toBlock(const HashEntry& e) { return {e.pos.x, e.pos.y, e.pos.z}; }

}  // namespace

VoxelBlockHash::VoxelBlockHash(const Settings& settings) : settings_(settings) {
    validate(settings_);
    entries_.allocate(std::size_t(settings_.bucket_count) * settings_.entries_per_bucket + settings_.excess_entry_count, true, false);
    free_excess_.allocate(std::size_t(settings_.excess_entry_count), true, false);
    free_blocks_.allocate(std::size_t(settings_.max_block_count), true, false);
    visible_entries_.allocate(std::size_t(settings_.max_block_count), true, false);
    clearBlocks();
}

VoxelBlockHash::Data VoxelBlockHash::data() const {
    return Data{entries_.host(), settings_.bucket_count, settings_.entries_per_bucket,
                settings_.bucket_count * settings_.entries_per_bucket, settings_.excess_entry_count};
}

void VoxelBlockHash::clearBlocks() {
    entries_.fillHost(HashEntry::empty());
    // Popped from the top: excess entry 0 and (after growth) block 0 are used first.
    free_excess_count_ = settings_.excess_entry_count;
    for (int i = 0; i < free_excess_count_; ++i) free_excess_.host()[i] = free_excess_count_ - 1 - i;
    block_capacity_ = 0;
    free_block_count_ = 0;
    visible_count_ = 0;
    visible_valid_ = false;
    stats_ = AllocationStats();
}

bool VoxelBlockHash::growBlockCapacity(int blocks) {
    if (blocks <= block_capacity_ || !canGrow()) return false;
    const int step = std::max(settings_.blocks_per_growth, block_capacity_ / 4);
    const long long wanted = std::max<long long>(blocks, (long long)block_capacity_ + step);
    const long long rounded = (wanted + settings_.blocks_per_growth - 1) / settings_.blocks_per_growth * settings_.blocks_per_growth;
    const int capacity = int(std::min<long long>(rounded, settings_.max_block_count));
    // New blocks go under the free ones already stacked, highest first, so that low indices are used first.
    int* stack = free_blocks_.host();
    const int added = capacity - block_capacity_;
    std::memmove(stack + added, stack, std::size_t(free_block_count_) * sizeof(int));
    for (int i = 0; i < added; ++i) stack[i] = capacity - 1 - i;
    free_block_count_ += added;
    block_capacity_ = capacity;
    stats_.block_capacity = capacity;
    return true;
}

int VoxelBlockHash::popFreeBlock() { return free_block_count_ > 0 ? free_blocks_.host()[--free_block_count_] : -1; }

int VoxelBlockHash::popFreeExcessEntry() { return free_excess_count_ > 0 ? free_excess_.host()[--free_excess_count_] : -1; }

int VoxelBlockHash::findEntry(Vec3i block) const {
    if (!blockIsAddressable(block)) return -1;
    return findHashEntry(data(), block);
}

VoxelBlockHash::InsertResult VoxelBlockHash::insert(Vec3i block, int* entry_out) {
    if (!blockIsAddressable(block)) return InsertResult::OutOfRange;
    int target;
    const int found = findHashEntry(data(), block, target);
    if (found >= 0) {
        if (entry_out) *entry_out = found;
        return InsertResult::AlreadyPresent;
    }
    return insertAt(target, block, entry_out);
}

VoxelBlockHash::InsertResult VoxelBlockHash::insertAt(int target, Vec3i block, int* entry_out) {
    if (!blockIsAddressable(block)) return InsertResult::OutOfRange;
    HashEntry* entries = entries_.host();
    const bool into_bucket = target < data().ordered_entry_count && entries[target].ptr == kEntryFree;
    if (free_block_count_ == 0) return InsertResult::NoVoxelBlock;
    if (!into_bucket && free_excess_count_ == 0) return InsertResult::NoHashEntry;
    const int ptr = popFreeBlock();
    int index = target;
    if (into_bucket) {
        entries[target].pos = toEntryPos(block);  // keeps `next`: a bucket's last entry may carry its chain
        entries[target].ptr = ptr;
    } else {
        const int excess = popFreeExcessEntry();
        index = data().ordered_entry_count + excess;
        entries[index] = HashEntry{toEntryPos(block), kEndOfChain, ptr};
        entries[target].next = excess;
    }
    ++stats_.blocks_allocated;
    if (entry_out) *entry_out = index;
    return InsertResult::Inserted;
}

void VoxelBlockHash::removeEntry(int index) {
    HashEntry* entries = entries_.host();
    const Data h = data();
    const HashEntry removed = entries[index];
    if (removed.ptr >= 0) free_blocks_.host()[free_block_count_++] = removed.ptr;
    --stats_.blocks_allocated;
    ++stats_.blocks_removed_total;

    const int first = hashBucket(toBlock(removed), h.bucket_count) * h.entries_per_bucket;
    const int last = first + h.entries_per_bucket - 1;
    if (index < h.ordered_entry_count) {
        const int head = entries[last].next;
        if (head == kEndOfChain) {
            entries[index].ptr = kEntryFree;  // `next` stays kEndOfChain
            return;
        }
        // Keep the bucket full while it has a chain: the chain head moves into the freed entry.
        const HashEntry moved = entries[h.ordered_entry_count + head];
        entries[index].pos = moved.pos;
        entries[index].ptr = moved.ptr;
        entries[last].next = moved.next;
        entries[h.ordered_entry_count + head] = HashEntry::empty();
        free_excess_.host()[free_excess_count_++] = head;
        return;
    }
    // An excess entry: unlink it from its predecessor.
    const int excess = index - h.ordered_entry_count;
    int prev = last;
    while (entries[prev].next != excess) prev = h.ordered_entry_count + entries[prev].next;
    entries[prev].next = removed.next;
    entries[index] = HashEntry::empty();
    free_excess_.host()[free_excess_count_++] = excess;
}

int VoxelBlockHash::removeBlocks(const std::vector<Vec3i>& blocks) {
    // Removal moves entries, so the visible list is kept as block positions meanwhile.
    std::vector<Vec3i> visible(static_cast<std::size_t>(visible_count_));
    for (int i = 0; i < visible_count_; ++i) visible[std::size_t(i)] = toBlock(entry(visible_entries_.host()[i]));

    int removed = 0;
    for (const Vec3i& b : blocks) {
        const int e = findEntry(b);
        if (e < 0) continue;
        removeEntry(e);
        ++removed;
    }
    int kept = 0;
    for (const Vec3i& b : visible) {
        const int e = findEntry(b);
        if (e >= 0 && entry(e).ptr >= 0) visible_entries_.host()[kept++] = e;
    }
    visible_count_ = kept;
    stats_.visible_blocks = kept;
    return removed;
}

void VoxelBlockHash::setVisibleEntries(const std::vector<int>& entries, const Mat4f& T_world_camera, const Intrinsics& intrinsics) {
    visible_count_ = int(std::min<std::size_t>(entries.size(), visible_entries_.size()));
    std::copy(entries.begin(), entries.begin() + visible_count_, visible_entries_.host());
    visible_valid_ = true;
    visible_T_world_camera_ = T_world_camera;
    visible_intrinsics_ = intrinsics;
    stats_.visible_blocks = visible_count_;
}

bool VoxelBlockHash::visibleListIsFor(const Mat4f& T_world_camera, const Intrinsics& intrinsics) const {
    const Intrinsics& a = visible_intrinsics_;
    const Intrinsics& b = intrinsics;
    return visible_valid_ && std::memcmp(visible_T_world_camera_.m, T_world_camera.m, sizeof(T_world_camera.m)) == 0 &&
           a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy && a.cx == b.cx && a.cy == b.cy;
}

}  // namespace voxfuse
