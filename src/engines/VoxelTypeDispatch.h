#pragma once
// Run-time voxel types (VoxelType) to the compile-time voxel structs: the one place where they meet.

#include "voxfuse/core/Error.h"
#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/objects/Voxel.h"

namespace voxfuse {

template <class TVoxel>
struct VoxelTag {
    using Voxel = TVoxel;
};

constexpr VoxelType kVoxelTypes[] = {VoxelType::S,    VoxelType::F,      VoxelType::SRgb,
                                     VoxelType::FRgb, VoxelType::SLabel, VoxelType::SRgbLabel};

// Calls f(VoxelTag<TVoxel>{}) for the voxel struct that `type` names: the one place where run-time
// voxel types meet the compile-time ones.
template <class F>
auto visitVoxelType(VoxelType type, F&& f) {
    switch (type) {
        case VoxelType::S:
            return f(VoxelTag<VoxelS>{});
        case VoxelType::F:
            return f(VoxelTag<VoxelF>{});
        case VoxelType::SRgb:
            return f(VoxelTag<VoxelSRgb>{});
        case VoxelType::FRgb:
            return f(VoxelTag<VoxelFRgb>{});
        case VoxelType::SLabel:
            return f(VoxelTag<VoxelSLabel>{});
        case VoxelType::SRgbLabel:
            return f(VoxelTag<VoxelSRgbLabel>{});
    }
    throw ConfigError("unknown voxel type " + std::to_string(int(type)));
}

}  // namespace voxfuse
