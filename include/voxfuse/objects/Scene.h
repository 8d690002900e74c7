#pragma once
// The map: voxel storage addressed through an index, plus the settings it was built with.

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/core/MemoryBlock.h"
#include "voxfuse/objects/SceneParams.h"

namespace voxfuse {

template <class TVoxel, class TIndex>
class Scene {
public:
    using Voxel = TVoxel;
    using Index = TIndex;

    // Allocates the voxel storage where `location` says and sets every voxel to TVoxel::initial() on the host.
    Scene(const SceneParams& params, const TIndex& index, Device location)
        : params_(params), index_(index), location_(location) {
        voxels_.allocate(index_.voxelCount(), true, location == Device::CUDA);
        voxels_.fillHost(TVoxel::initial());
        if (location == Device::CUDA) voxels_.copyHostToDevice();
    }

    const SceneParams& params() const { return params_; }
    TIndex& index() { return index_; }
    const TIndex& index() const { return index_; }
    MemoryBlock<TVoxel>& voxels() { return voxels_; }
    const MemoryBlock<TVoxel>& voxels() const { return voxels_; }
    // Where the authoritative copy lives (engines of the other device must copy explicitly).
    Device location() const { return location_; }

private:
    SceneParams params_;
    TIndex index_;
    MemoryBlock<TVoxel> voxels_;
    Device location_;
};

}  // namespace voxfuse
