// The voxel block hash's storage on its device, its host-side operations, and growth.

#include "voxfuse/objects/VoxelBlockHash.h"

#include <algorithm>
#include <climits>
#include <cstring>
#include <set>
#include <string>

#include "voxfuse/core/Error.h"
#include "voxfuse/shared/HashAccess.h"
#include "voxfuse/shared/HashUpdate.h"

namespace voxfuse {
namespace {

void validate(const VoxelBlockHashSettings& s) {
    auto fail = [](const std::string& what) { throw ConfigError("voxel block hash: " + what); };
    if (s.bucket_count < 1) fail("bucket count must be positive (got " + std::to_string(s.bucket_count) + ")");
    if (s.entries_per_bucket != 1 && s.entries_per_bucket != 2)
        fail("entries per bucket must be 1 or 2 (got " + std::to_string(s.entries_per_bucket) + ")");
    if (s.excess_entry_count < 0)
        fail("excess list size must not be negative (got " + std::to_string(s.excess_entry_count) + ")");
    if ((long long)s.bucket_count * s.entries_per_bucket + s.excess_entry_count > INT_MAX)
        fail("too many hash entries");
    // Voxel offsets ptr * 512 + i are ints: 2^22 blocks (2^31 voxels) at most.
    if (s.max_block_count < 1 || s.max_block_count > (1 << 22))
        fail("maximum block count must be in 1..4194304 (got " + std::to_string(s.max_block_count) + ")");
    if (s.max_bucket_count < 0)
        fail("maximum bucket count must not be negative (got " + std::to_string(s.max_bucket_count) + ")");
    if ((long long)std::max(s.bucket_count, s.max_bucket_count) * s.entries_per_bucket +
            (long long)s.excess_entry_count * std::max(1, s.max_bucket_count / s.bucket_count) >
        INT_MAX)
        fail("too many hash entries once the table has grown");
    if (s.blocks_per_growth < 1)
        fail("blocks per growth must be positive (got " + std::to_string(s.blocks_per_growth) + ")");
}

template <class T>
void allocateOn(MemoryBlock<T>& block, std::size_t count, Device where) {
    block.allocate(count, where == Device::CPU, where == Device::CUDA);
}

}  // namespace

VoxelBlockHash::VoxelBlockHash(const Settings& settings, Device location) : VoxelBlockHash(settings, location, true) {}

std::size_t VoxelBlockHash::tableBytesFor(const Settings& s) {
    const std::size_t entries =
        std::size_t(s.bucket_count) * std::size_t(s.entries_per_bucket) + std::size_t(s.excess_entry_count);
    return entries * (sizeof(HashEntry) + sizeof(std::uint8_t) + sizeof(int)) +
           (std::size_t(s.excess_entry_count) + 2 * std::size_t(s.max_block_count)) * sizeof(int);
}

namespace {

// One doubling of a growable table: its buckets (at most to max_bucket_count) and its excess list.
VoxelBlockHashSettings doubled(const VoxelBlockHashSettings& s) {
    VoxelBlockHashSettings grown = s;
    grown.bucket_count = int(std::min<long long>(s.max_bucket_count, 2LL * s.bucket_count));
    grown.excess_entry_count = int((long long)s.excess_entry_count * grown.bucket_count / s.bucket_count);
    return grown;
}

bool overLoad(const VoxelBlockHashSettings& s, double blocks) {
    return blocks > double(kMaxBucketLoad) * double(s.bucket_count) * double(s.entries_per_bucket);
}

}  // namespace

VoxelBlockHash::Settings VoxelBlockHash::fullyGrown(const Settings& s) {
    Settings grown = s;
    while (grown.bucket_count < s.max_bucket_count) grown = doubled(grown);
    return grown;
}

VoxelBlockHash::VoxelBlockHash(const Settings& settings, Device location, bool allocate_tables)
    : settings_(settings), location_(location) {
    validate(settings_);
    if (!allocate_tables) return;
    const std::size_t entries =
        std::size_t(settings_.bucket_count) * settings_.entries_per_bucket + settings_.excess_entry_count;
    allocateOn(entries_, entries, location_);
    allocateOn(entry_visibility_, entries, location_);
    allocateOn(stored_slot_, entries, location_);
    allocateOn(free_excess_, std::size_t(settings_.excess_entry_count), location_);
    allocateOn(free_blocks_, std::size_t(settings_.max_block_count), location_);
    allocateOn(visible_entries_, std::size_t(settings_.max_block_count), location_);
    clearBlocks();
}

void VoxelBlockHash::moveTo(Device where) {
    if (where == location_) return;
    keepOnly(entries_, where);
    keepOnly(entry_visibility_, where);
    keepOnly(stored_slot_, where);
    keepOnly(free_excess_, where);
    keepOnly(free_blocks_, where);
    keepOnly(visible_entries_, where);
    location_ = where;
}

VoxelBlockHash VoxelBlockHash::copyTo(Device where) const {
    VoxelBlockHash copy(settings_, where, false);
    allocateOn(copy.entries_, entries_.size(), where);
    allocateOn(copy.entry_visibility_, entry_visibility_.size(), where);
    allocateOn(copy.stored_slot_, stored_slot_.size(), where);
    allocateOn(copy.free_excess_, free_excess_.size(), where);
    allocateOn(copy.free_blocks_, free_blocks_.size(), where);
    allocateOn(copy.visible_entries_, visible_entries_.size(), where);
    copyAcross(copy.entries_, where, entries_, location_);
    copyAcross(copy.entry_visibility_, where, entry_visibility_, location_);
    copyAcross(copy.stored_slot_, where, stored_slot_, location_);
    copyAcross(copy.free_excess_, where, free_excess_, location_);
    copyAcross(copy.free_blocks_, where, free_blocks_, location_);
    copyAcross(copy.visible_entries_, where, visible_entries_, location_);
    copyBookkeepingTo(copy);
    copy.free_excess_count_ = free_excess_count_;
    return copy;
}

void VoxelBlockHash::copyBookkeepingTo(VoxelBlockHash& to) const {
    to.free_block_count_ = free_block_count_;
    to.block_capacity_ = block_capacity_;
    to.stored_block_count_ = stored_block_count_;
    to.visible_count_ = visible_count_;
    to.visible_valid_ = visible_valid_;
    to.visible_T_world_camera_ = visible_T_world_camera_;
    to.visible_intrinsics_ = visible_intrinsics_;
    to.stats_ = stats_;
}

VoxelBlockHash::Data VoxelBlockHash::data() const {
    return Data{entries_.data(location_), settings_.bucket_count, settings_.entries_per_bucket,
                settings_.bucket_count * settings_.entries_per_bucket, settings_.excess_entry_count};
}

HashTableState VoxelBlockHash::state() {
    return HashTableState{entries_.data(location_),
                          free_blocks_.data(location_),
                          free_excess_.data(location_),
                          entry_visibility_.data(location_),
                          stored_slot_.data(location_),
                          entryCount(),
                          settings_.bucket_count,
                          settings_.entries_per_bucket,
                          settings_.bucket_count * settings_.entries_per_bucket,
                          settings_.excess_entry_count};
}

void VoxelBlockHash::clearBlocks() {
    entries_.fill(location_, HashEntry::empty(), 0, entries_.size());
    entry_visibility_.fill(location_, kEntryNotVisible, 0, entry_visibility_.size());
    stored_slot_.fill(location_, kNoStoredCopy, 0, stored_slot_.size());
    // Popped from the top: excess entry 0 is used first.
    std::vector<int> excess(std::size_t(settings_.excess_entry_count));
    for (int i = 0; i < settings_.excess_entry_count; ++i)
        excess[std::size_t(i)] = settings_.excess_entry_count - 1 - i;
    free_excess_.writeRange(location_, 0, excess.data(), excess.size());
    free_excess_count_ = settings_.excess_entry_count;
    block_capacity_ = 0;
    free_block_count_ = 0;
    stored_block_count_ = 0;
    visible_count_ = 0;
    visible_valid_ = false;
    stats_ = AllocationStats();
}

bool VoxelBlockHash::wantsMoreBuckets(int adding) const {
    return settings_.max_bucket_count > settings_.bucket_count &&
           overLoad(settings_, double(blocksInUse()) + double(storedBlocks()) + double(adding));
}

void VoxelBlockHash::growBuckets(int adding) {
    if (settings_.max_bucket_count <= settings_.bucket_count) return;
    Settings grown = doubled(settings_);
    const double blocks = double(blocksInUse()) + double(storedBlocks()) + double(adding);
    while (grown.bucket_count < grown.max_bucket_count && overLoad(grown, blocks)) grown = doubled(grown);
    const Device where = location_;
    moveTo(Device::CPU);
    VoxelBlockHash fresh(grown, Device::CPU);
    // In entry order, so that the new table (and the visible list) does not depend on threads.
    std::vector<int> moved_to(std::size_t(entryCount()), -1);
    const HashEntry* old_entries = entries_.host();
    for (int i = 0; i < entryCount(); ++i) {
        const HashEntry& e = old_entries[i];
        if (e.ptr == kEntryFree) continue;
        const Vec3i block{e.pos.x, e.pos.y, e.pos.z};
        int target, at;
        if (findHashEntry(fresh.data(), block, target) >= 0 || !fresh.insertEntry(target, block, e.ptr, &at))
            throw Error("voxel block hash: a block does not fit the grown table (" +
                        std::to_string(grown.bucket_count) + " buckets)");
        fresh.stored_slot_.host()[at] = stored_slot_.host()[i];
        fresh.entry_visibility_.host()[at] = entry_visibility_.host()[i];
        moved_to[std::size_t(i)] = at;
    }
    // The voxel blocks and their free stack stay; the visible list names the blocks' new entries.
    fresh.free_blocks_ = std::move(free_blocks_);
    fresh.visible_entries_ = std::move(visible_entries_);
    int* visible = fresh.visible_entries_.host();
    int kept = 0;
    for (int k = 0; k < visible_count_; ++k)
        if (moved_to[std::size_t(visible[k])] >= 0) visible[kept++] = moved_to[std::size_t(visible[k])];
    std::sort(visible, visible + kept);
    visible_count_ = kept;
    copyBookkeepingTo(fresh);
    *this = std::move(fresh);
    moveTo(where);
}

int VoxelBlockHash::grownBlockCapacity(int blocks) const {
    if (blocks <= block_capacity_ || !canGrow()) return block_capacity_;
    const int step = std::max(settings_.blocks_per_growth, block_capacity_ / 4);
    const long long wanted = std::max<long long>(blocks, (long long)block_capacity_ + step);
    const long long rounded =
        (wanted + settings_.blocks_per_growth - 1) / settings_.blocks_per_growth * settings_.blocks_per_growth;
    return int(std::min<long long>(rounded, settings_.max_block_count));
}

void VoxelBlockHash::setBlockCapacity(int capacity) {
    if (capacity <= block_capacity_) return;
    // The new blocks go on top of the stack, highest first, so that they are taken in ascending order.
    const int added = capacity - block_capacity_;
    std::vector<int> fresh(static_cast<std::size_t>(added));
    for (int i = 0; i < added; ++i) fresh[std::size_t(i)] = capacity - 1 - i;
    free_blocks_.writeRange(location_, std::size_t(free_block_count_), fresh.data(), fresh.size());
    free_block_count_ += added;
    block_capacity_ = capacity;
    stats_.block_capacity = capacity;
}

void VoxelBlockHash::popFreeStacks(int blocks, int excess_entries) {
    free_block_count_ -= blocks;
    free_excess_count_ -= excess_entries;
    if (free_block_count_ < 0 || free_block_count_ > block_capacity_ || free_excess_count_ < 0 ||
        free_excess_count_ > settings_.excess_entry_count)
        throw Error("voxel block hash: free stacks out of range after a device update (" +
                    std::to_string(free_block_count_) + " blocks, " + std::to_string(free_excess_count_) +
                    " excess entries)");
}

void VoxelBlockHash::requireHost(const char* what) const {
    if (location_ != Device::CPU)
        throw DeviceError(std::string("voxel block hash: ") + what +
                          " works on a hash in host memory; this one is on the GPU " +
                          "(take a host copy with copyTo(Device::CPU))");
}

const HashEntry& VoxelBlockHash::entry(int i) const {
    requireHost("entry()");
    return entries_.host()[i];
}

int VoxelBlockHash::findEntry(Vec3i block) const {
    requireHost("findEntry()");
    if (!blockIsAddressable(block)) return -1;
    return findHashEntry(data(), block);
}

VoxelBlockHash::InsertResult VoxelBlockHash::insert(Vec3i block, int* entry_out) {
    requireHost("insert()");
    if (!blockIsAddressable(block)) return InsertResult::OutOfRange;
    int target;
    const int found = findHashEntry(data(), block, target);
    if (found >= 0) {
        if (entry_out) *entry_out = found;
        return InsertResult::AlreadyPresent;
    }
    if (free_block_count_ == 0) return InsertResult::NoVoxelBlock;
    if (!insertEntry(target, block, free_blocks_.host()[free_block_count_ - 1], entry_out))
        return InsertResult::NoHashEntry;
    --free_block_count_;
    ++stats_.blocks_allocated;
    return InsertResult::Inserted;
}

VoxelBlockHash::InsertResult VoxelBlockHash::insertStored(Vec3i block, int slot, int* entry_out) {
    requireHost("insertStored()");
    if (!blockIsAddressable(block)) return InsertResult::OutOfRange;
    int target;
    const int found = findHashEntry(data(), block, target);
    if (found >= 0) {
        if (entry_out) *entry_out = found;
        return InsertResult::AlreadyPresent;
    }
    int entry;
    if (!insertEntry(target, block, kEntrySwappedOut, &entry)) return InsertResult::NoHashEntry;
    stored_slot_.host()[entry] = slot;
    ++stored_block_count_;
    if (entry_out) *entry_out = entry;
    return InsertResult::Inserted;
}

bool VoxelBlockHash::insertEntry(int target, Vec3i block, int ptr, int* entry_out) {
    HashEntry* entries = entries_.host();
    const bool into_bucket = target < data().ordered_entry_count && entries[target].ptr == kEntryFree;
    if (!into_bucket && free_excess_count_ == 0) return false;
    const Vec3<std::int16_t> pos{std::int16_t(block.x), std::int16_t(block.y), std::int16_t(block.z)};
    int index = target;
    if (into_bucket) {
        entries[target].pos = pos;  // keeps `next`: a bucket's last entry may carry its chain
        entries[target].ptr = ptr;
    } else {
        const int excess = free_excess_.host()[--free_excess_count_];
        index = data().ordered_entry_count + excess;
        entries[index] = HashEntry{pos, kEndOfChain, ptr};
        entries[target].next = excess;
    }
    if (entry_out) *entry_out = index;
    return true;
}

int VoxelBlockHash::removeBlocks(const std::vector<Vec3i>& blocks) {
    requireHost("removeBlocks()");
    std::vector<std::uint8_t> remove(entries_.size(), 0);
    std::set<int> buckets;
    int removed = 0;
    for (const Vec3i& b : blocks) {
        const int e = findEntry(b);
        // Active blocks only: a block with a stored copy is not dropped here.
        if (e < 0 || entries_.host()[e].ptr < 0 || stored_slot_.host()[e] != kNoStoredCopy || remove[std::size_t(e)])
            continue;
        remove[std::size_t(e)] = 1;
        buckets.insert(hashBucket(b, settings_.bucket_count));
        ++removed;
    }
    // The parallel removal's two passes, bucket by bucket: count, then remove at the running offsets.
    std::vector<int> freed_blocks(std::size_t(settings_.bucket_count), 0),
        freed_excess(std::size_t(settings_.bucket_count), 0);
    BucketRemoval r{state(),           remove.data(),     freed_blocks.data(), freed_excess.data(),
                    free_block_count_, free_excess_count_};
    int block_offset = 0, excess_offset = 0;
    for (int bucket : buckets) {
        CountBucketRemovals{r}(bucket);
        const int blocks_here = freed_blocks[std::size_t(bucket)], excess_here = freed_excess[std::size_t(bucket)];
        freed_blocks[std::size_t(bucket)] = block_offset;
        freed_excess[std::size_t(bucket)] = excess_offset;
        RemoveBucketEntries{r}(bucket);
        block_offset += blocks_here;
        excess_offset += excess_here;
    }
    popFreeStacks(-block_offset, -excess_offset);
    stats_.blocks_allocated -= removed;
    stats_.blocks_removed_total += removed;

    // The visible list: the entries still marked visible (removal moved marks with their entries).
    std::vector<int> visible;
    for (int i = 0; i < entryCount(); ++i)
        if (entry_visibility_.host()[i] == kEntryVisible) visible.push_back(i);
    std::copy(visible.begin(), visible.end(), visible_entries_.host());
    setVisibleCount(int(visible.size()));
    return removed;
}

void VoxelBlockHash::setVisibleEntries(const std::vector<int>& entries, const Mat4f& T_world_camera,
                                       const Intrinsics& intrinsics) {
    requireHost("setVisibleEntries()");
    const int count = int(std::min<std::size_t>(entries.size(), visible_entries_.size()));
    std::fill(entry_visibility_.host(), entry_visibility_.host() + entry_visibility_.size(), kEntryNotVisible);
    for (int k = 0; k < count; ++k) entry_visibility_.host()[entries[std::size_t(k)]] = kEntryVisible;
    std::copy(entries.begin(), entries.begin() + count, visible_entries_.host());
    setVisibleListFor(count, T_world_camera, intrinsics);
}

void VoxelBlockHash::setVisibleListFor(int count, const Mat4f& T_world_camera, const Intrinsics& intrinsics) {
    visible_count_ = count;
    visible_valid_ = true;
    visible_T_world_camera_ = T_world_camera;
    visible_intrinsics_ = intrinsics;
    stats_.visible_blocks = visible_count_;
}

void VoxelBlockHash::setVisibleCount(int count) {
    visible_count_ = count;
    stats_.visible_blocks = count;
}

bool VoxelBlockHash::visibleListCovers(const Mat4f& T_world_camera, const Intrinsics& intrinsics) const {
    if (!visible_valid_ || std::memcmp(visible_T_world_camera_.m, T_world_camera.m, sizeof(T_world_camera.m)) != 0)
        return false;
    if (intrinsics.width <= 0 || intrinsics.height <= 0) return false;
    const int factor = visible_intrinsics_.width / intrinsics.width;
    if (factor < 1) return false;
    // (cx + 0.5) - 0.5 need not give cx back in floats: factor 1 compares the list's own.
    const Intrinsics a = factor == 1 ? visible_intrinsics_ : visible_intrinsics_.downsampled(factor);
    const Intrinsics& b = intrinsics;
    return a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy && a.cx == b.cx && a.cy == b.cy;
}

}  // namespace voxfuse
