#pragma once
// The map: voxel storage addressed through an index, plus the settings it was built with.

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <utility>

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/core/MemoryBlock.h"
#include "voxfuse/objects/SceneParams.h"

namespace voxfuse {

template <class TVoxel, class TIndex>
class Scene {
public:
    using Voxel = TVoxel;
    using Index = TIndex;

    // Allocates the voxel storage the index asks for, where `location` says, and sets every voxel to
    // TVoxel::initial(). The index is moved in (the hash index owns large tables and is not copyable).
    Scene(const SceneParams& params, TIndex index, Device location)
        : params_(params), index_(std::move(index)), location_(location) {
        resizeVoxelStorage(index_.voxelCount());
    }

    const SceneParams& params() const { return params_; }
    TIndex& index() { return index_; }
    const TIndex& index() const { return index_; }
    MemoryBlock<TVoxel>& voxels() { return voxels_; }
    const MemoryBlock<TVoxel>& voxels() const { return voxels_; }
    // Where the authoritative copy lives (engines of the other device must copy explicitly).
    Device location() const { return location_; }
    // Each call of an integration engine takes the next number (from 0). Label fusion draws its random
    // numbers from it: they differ from frame to frame whatever indices the caller gives its frames.
    std::uint32_t takeIntegrationNumber() { return integrations_++; }

    // ---- Indexes whose storage grows (VoxelBlockHash); not instantiated for the others ----

    // Backs at least `blocks` voxel blocks with memory, as far as the index's maximum allows; the index
    // picks the new capacity. Voxel contents are kept, but the arrays move: every pointer into voxels()
    // taken before this call is invalid. Engines take their voxel pointers at the start of a stage and
    // never keep them, and only the allocation engine calls this, between its stages, before it takes any.
    void reserveVoxelBlocks(int blocks) {
        if (index_.growBlockCapacity(blocks)) resizeVoxelStorage(index_.voxelCount());
    }
    // Empties the map and returns the voxel storage to the size of a new scene.
    void clearVoxelBlocks() {
        index_.clearBlocks();
        voxels_ = MemoryBlock<TVoxel>();
        resizeVoxelStorage(index_.voxelCount());
    }

private:
    // Reallocates the voxels (host, plus device for a CUDA scene) to `count`, keeping the first
    // min(count, old size) and setting the rest to TVoxel::initial().
    void resizeVoxelStorage(std::size_t count) {
        const bool on_device = location_ == Device::CUDA;
        MemoryBlock<TVoxel> resized(count, true, on_device);
        const std::size_t kept = std::min(count, voxels_.size());
        if (kept) std::memcpy(static_cast<void*>(resized.host()), voxels_.host(), kept * sizeof(TVoxel));
        std::fill(resized.host() + kept, resized.host() + count, TVoxel::initial());
        if (on_device && count > 0) {
            if (kept) device_memory::copyDeviceToDevice(resized.device(), voxels_.device(), kept * sizeof(TVoxel));
            device_memory::copyHostToDevice(resized.device() + kept, resized.host() + kept, (count - kept) * sizeof(TVoxel));
        }
        voxels_ = std::move(resized);
    }

    SceneParams params_;
    TIndex index_;
    MemoryBlock<TVoxel> voxels_;
    Device location_;
    std::uint32_t integrations_ = 0;
};

}  // namespace voxfuse
