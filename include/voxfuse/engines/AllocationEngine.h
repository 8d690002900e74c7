#pragma once
// Preparing the index for a depth frame (section 4.2 of the InfiniTAM report). For the voxel block hash,
// in three stages:
//   1. per depth pixel, walk the segment [d - mu, d + mu] through block space and mark each block as
//      visible (allocated) or to be allocated (plain writes, no critical sections: of two new blocks that
//      want the same hash entry in one frame only one is marked);
//   2. allocate the marked blocks from the free stacks (ordered bucket entry if free, else excess list),
//      growing the voxel block array first when it needs more blocks; the CPU layer then also inserts
//      the blocks that lost such a collision (the report leaves them to the next frame);
//   3. build the visible list: blocks marked in stage 1 or 2, plus previously visible blocks that are
//      still in the view frustum. Integration updates exactly these blocks.
// A full table or block array is counted in AllocationStats, never silent. The dense index needs no
// allocation: its engine does nothing, so that the main engine runs one pipeline for both.
// Device layers: src/cpu/AllocationEngine_CPU.cpp; per-pixel work in shared/Allocation.h.

#include <memory>
#include <type_traits>

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

// The dense engine does nothing and serves every device. The hash has no CUDA layer yet: asking for
// one throws DeviceError.
template <class TVoxel, class TIndex>
std::unique_ptr<AllocationEngine<TVoxel, TIndex>> makeAllocationEngine(Device device) {
    if (!std::is_same<TIndex, PlainVoxelArray>::value && device != Device::CPU)
        throw DeviceError("the hash allocation engine has no CUDA layer yet: use the CPU device");
    return cpu::makeAllocationEngine<TVoxel, TIndex>();
}

}  // namespace voxfuse
