#pragma once
// Swapping (section 5 of the InfiniTAM report): only the part of a voxel block hash near the live view
// stays in the active voxel array (on the GPU with Device::CUDA, else a bounded CPU array); the rest
// moves to the global cache (objects/GlobalCache.h: host memory or a file). Each call moves at most a
// fixed number of blocks, through fixed-size transfer buffers, so a frame's cost is bounded whatever
// the cache's storage is.
//
// Per frame, in the main engine's order:
//   allocation   stored blocks the depth needs get a voxel block again (merge pending: their stored copy
//                still waits in the cache) and fuse this frame's data from now on; then the stored blocks
//                the raycast from this pose can read (shared/BlockProjection.h, RaycastReach), which fuse
//                nothing, in the room the array has beyond a reserve for the view (reachReserveBlocks);
//   swapIn       merges up to `max_blocks` waiting stored copies into their blocks, those of the visible
//                list first, lowest entry first (the InfiniTAM report's secondary integration: never
//                overwriting what was fused meanwhile);
//   integration, raycast;
//   swapOut      moves up to `max_blocks` active blocks that are neither in the visible list nor in the
//                raycast's reach (and wait for nothing) to the cache, lowest entry first, and frees their
//                voxel blocks; then, while the array has less room than the reserve, blocks in the reach.
// The active part of the map is thus what the report calls the part "inside or close to the current view
// frustum". When every waiting copy arrives in the frame that needs it and the array holds the raycast's
// reach beside the reserve, the map and the raycasts from the tracked poses (so the poses too) are bit for bit those of
// a run without swapping; raycasts from elsewhere (relocalisation's candidates, free-view renders) read only what is
// active. Stages: src/engines/SwappingEngine_Impl.h, run by src/cpu/SwappingEngine_CPU.cpp and
// cuda/SwappingEngine_CUDA.cu; per-element work in shared/Swapping.h.

#include <memory>

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/objects/GlobalCache.h"
#include "voxfuse/objects/Scene.h"
#include "voxfuse/objects/VoxelBlockHash.h"

namespace voxfuse {

template <class TVoxel>
class SwappingEngine {
public:
    virtual ~SwappingEngine() = default;
    // Returns the blocks moved (each at most max_blocks).
    virtual int swapIn(Scene<TVoxel, VoxelBlockHash>& scene, GlobalCache& cache, int max_blocks) = 0;
    virtual int swapOut(Scene<TVoxel, VoxelBlockHash>& scene, GlobalCache& cache, int max_blocks) = 0;
};

namespace cpu {
template <class TVoxel>
std::unique_ptr<SwappingEngine<TVoxel>> makeSwappingEngine();
}
namespace cuda {
template <class TVoxel>
std::unique_ptr<SwappingEngine<TVoxel>> makeSwappingEngine();
}

// The engine of `device`; DeviceError in a build without CUDA.
template <class TVoxel>
std::unique_ptr<SwappingEngine<TVoxel>> makeSwappingEngine(Device device) {
    return device == Device::CPU ? cpu::makeSwappingEngine<TVoxel>() : cuda::makeSwappingEngine<TVoxel>();
}

}  // namespace voxfuse
