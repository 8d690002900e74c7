#pragma once
// Preparing the index for a depth frame (section 4.2 of the InfiniTAM report). For the voxel block hash,
// in three stages:
//   1. per depth pixel, walk the segment [d - mu, d + mu] through block space and mark each block as
//      visible (allocated) or to be allocated (plain writes, no critical sections: of two new blocks that
//      want the same hash entry in one frame only one is marked);
//   2. allocate the missing blocks from the free stacks (ordered bucket entry if free, else excess list),
//      growing the voxel block array first when it needs more blocks. Unlike the InfiniTAM report,
//      which leaves a block that lost an intra-frame collision (two new blocks, one insertion target)
//      to the next frame, every missing block is inserted in the frame that needs it: insertion runs
//      in rounds, one block per target and round (shared/HashUpdate.h);
//   3. build the visible list: blocks marked in stage 1 or 2, plus previously visible blocks that are
//      still in the view frustum. Integration updates exactly these blocks.
// A full table or block array is counted in AllocationStats, never silent. For the same frames the CPU
// and CUDA layers build the same table, entry for entry. The dense index needs no allocation: its
// engine does nothing, so that the main engine runs one pipeline for both.
// Stages: src/engines/AllocationEngine_Impl.h, run by src/cpu/AllocationEngine_CPU.cpp and
// cuda/AllocationEngine_CUDA.cu; per-element work in shared/Allocation.h and shared/HashUpdate.h.

#include <memory>

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/objects/AllocationStats.h"
#include "voxfuse/objects/PlainVoxelArray.h"
#include "voxfuse/objects/Scene.h"
#include "voxfuse/objects/View.h"
#include "voxfuse/objects/VoxelBlockHash.h"
#include "voxfuse/shared/Allocation.h"

namespace voxfuse {

template <class TVoxel, class TIndex>
class AllocationEngine {
public:
    virtual ~AllocationEngine() = default;
    // Allocates the blocks that `view`, seen from the depth camera pose T_world_camera, needs and builds the
    // visible list for it. Call before integrating (and raycasting) this view. Returns the index's
    // statistics after this frame (all zero for the dense index).
    virtual AllocationStats allocate(Scene<TVoxel, TIndex>& scene, const View& view, const Mat4f& T_world_camera) = 0;
    // Returns the blocks that hold no information to the free stacks: a block is empty when none of its
    // 512 voxels has a depth weight above 0 (never updated since it was allocated, e.g. blocks of the
    // d + mu end of a segment that lie behind the surface). Weights never decrease, so a block that was
    // once updated stays. Cost: one pass over the allocated blocks (stops at the first observed voxel of
    // each), cheap enough for every few frames. Call between frames. Returns how many were removed.
    virtual int removeEmptyBlocks(Scene<TVoxel, TIndex>& scene) = 0;
};

// ---- Host-side logic shared by the device layers ----

// The per-frame constants of allocation stage 1 for `view` seen from T_world_camera.
DepthSegmentFrame makeDepthSegmentFrame(const SceneParams& params, const View& view, const Mat4f& T_world_camera);

namespace cpu {
template <class TVoxel, class TIndex>
std::unique_ptr<AllocationEngine<TVoxel, TIndex>> makeAllocationEngine();
}
namespace cuda {
template <class TVoxel, class TIndex>
std::unique_ptr<AllocationEngine<TVoxel, TIndex>> makeAllocationEngine();
}

// The engine of `device` for scenes on that device; DeviceError in a build without CUDA.
template <class TVoxel, class TIndex>
std::unique_ptr<AllocationEngine<TVoxel, TIndex>> makeAllocationEngine(Device device) {
    return device == Device::CPU ? cpu::makeAllocationEngine<TVoxel, TIndex>()
                                 : cuda::makeAllocationEngine<TVoxel, TIndex>();
}

}  // namespace voxfuse
