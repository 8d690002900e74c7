#pragma once
// The map: voxel storage addressed through an index, plus the settings it was built with. A scene
// lives on one device (location()): on the GPU its voxels and its hash table are in GPU memory only,
// with no host mirror to go stale. copyTo() makes an independent copy on another device (e.g. a host
// snapshot to write a mesh from, or to compare the two devices in a test).

#include <algorithm>
#include <cstdint>
#include <type_traits>
#include <utility>

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/core/MemoryBlock.h"
#include "voxfuse/objects/SceneParams.h"

namespace voxfuse {

class VoxelBlockHash;

template <class TVoxel, class TIndex>
class Scene {
public:
    using Voxel = TVoxel;
    using Index = TIndex;

    // Allocates the voxel storage the index asks for on `location` (moving the index there too): a dense
    // array's voxels set to TVoxel::initial(), a hash's blocks as resizeVoxelStorage says. The index is
    // moved in (the hash owns large tables).
    Scene(const SceneParams& params, TIndex index, Device location)
        : params_(params), index_(std::move(index)), location_(location) {
        if constexpr (std::is_same<TIndex, VoxelBlockHash>::value) index_.moveTo(location_);
        resizeVoxelStorage(index_.voxelCount());
    }
    Scene(Scene&&) = default;
    Scene& operator=(Scene&&) = default;

    const SceneParams& params() const { return params_; }
    TIndex& index() { return index_; }
    const TIndex& index() const { return index_; }
    // The voxels, on location() only.
    MemoryBlock<TVoxel>& voxels() { return voxels_; }
    const MemoryBlock<TVoxel>& voxels() const { return voxels_; }
    TVoxel* voxelData() { return voxels_.data(location_); }
    const TVoxel* voxelData() const { return voxels_.data(location_); }
    // Where the scene lives; engines of another device refuse it.
    Device location() const { return location_; }
    // Each call of an integration engine takes the next number (from 0). Label fusion draws its random
    // numbers from it: they differ from frame to frame whatever indices the caller gives its frames.
    std::uint32_t takeIntegrationNumber() { return integrations_++; }
    std::uint32_t integrationCount() const { return integrations_; }
    // A map read from a file continues the count it was saved with.
    void setIntegrationCount(std::uint32_t count) { integrations_ = count; }

    // An independent copy of the whole scene (index, voxels, integration count) on `where`.
    Scene copyTo(Device where) const {
        Scene copy(params_, copyIndex(where), where, NoVoxels{});
        copy.voxels_.allocate(voxels_.size(), where == Device::CPU, where == Device::CUDA);
        copyAcross(copy.voxels_, where, voxels_, location_);
        copy.integrations_ = integrations_;
        return copy;
    }

    // ---- Indexes whose storage grows (VoxelBlockHash); not instantiated for the others ----

    // Backs at least `blocks` voxel blocks with memory, as far as the index's maximum allows; the index
    // picks the new capacity. Voxel contents are kept, but the arrays may move (at the first growth on
    // the GPU, or where no address space could be reserved): every pointer into voxels() taken before
    // this call is invalid.
    // Engines take their voxel pointers at the start of a stage and never keep them, and only the
    // allocation engine calls this, between its stages, before it takes any.
    // The voxels grow first: if their allocation fails (a GPU holds the old and the new array at
    // once), the index still has its old capacity, and the scene is as it was.
    void reserveVoxelBlocks(int blocks) {
        const int capacity = index_.grownBlockCapacity(blocks);
        if (capacity == index_.blockCapacity()) return;
        resizeVoxelStorage(index_.voxelCountFor(capacity));
        index_.setBlockCapacity(capacity);
    }
    // Empties the map and returns the voxel storage to the size of a new scene.
    void clearVoxelBlocks() {
        index_.clearBlocks();
        voxels_ = MemoryBlock<TVoxel>();
        resizeVoxelStorage(index_.voxelCount());
    }

private:
    struct NoVoxels {};
    Scene(const SceneParams& params, TIndex index, Device location, NoVoxels)
        : params_(params), index_(std::move(index)), location_(location) {}

    TIndex copyIndex(Device where) const {
        if constexpr (std::is_same<TIndex, VoxelBlockHash>::value)
            return index_.copyTo(where);
        else
            return index_;
    }

    // Reallocates the voxels on location() to `count`, keeping the first min(count, old size). Where the
    // array grows in place, the new blocks are left as they are: a block is reset to TVoxel::initial()
    // when the allocation engine takes it off the free stack (or written whole by whoever inserts it),
    // so the capacity not yet used costs address space, not memory (a quarter of the map at most).
    void resizeVoxelStorage(std::size_t count) {
        if constexpr (std::is_same<TIndex, VoxelBlockHash>::value) {
            if (location_ == Device::CPU && !voxels_.onDevice() && count >= voxels_.size()) {
                // On the host the array grows inside address space reserved for the index's maximum:
                // the voxels stay where they are, and a growth costs nothing until blocks are used, not
                // a copy of the whole map (which stalls the frame that grows it).
                voxels_.growHost(count, index_.maxVoxelCount());
                return;
            }
            // On the GPU likewise, where it has virtual memory management (else the copy below).
            if (location_ == Device::CUDA && !voxels_.onHost() && count >= voxels_.size() &&
                voxels_.growDevice(count, index_.maxVoxelCount()))
                return;
        }
        MemoryBlock<TVoxel> resized(count, location_ == Device::CPU, location_ == Device::CUDA);
        const std::size_t kept = std::min(count, voxels_.size());
        resized.copyRangeFrom(location_, voxels_, 0, 0, kept);
        resized.fill(location_, TVoxel::initial(), kept, count - kept);
        voxels_ = std::move(resized);
    }

    SceneParams params_;
    TIndex index_;
    MemoryBlock<TVoxel> voxels_;
    Device location_;
    std::uint32_t integrations_ = 0;
};

}  // namespace voxfuse
