#pragma once
// The voxel/index pairs every engine is built for, in one place. A device layer instantiates its
// factory for all of them with
//   #define VF_INSTANTIATE(TVoxel, TIndex) template std::unique_ptr<Engine<TVoxel, TIndex>> makeEngine<TVoxel, TIndex>();
//   VF_FOR_EACH_ENGINE_PAIR(VF_INSTANTIATE)
// so that adding a voxel or index type is one line here.

#include "voxfuse/objects/PlainVoxelArray.h"
#include "voxfuse/objects/Voxel.h"
#include "voxfuse/objects/VoxelBlockHash.h"

#define VF_FOR_EACH_ENGINE_PAIR(MACRO)     \
    MACRO(VoxelS, PlainVoxelArray)         \
    MACRO(VoxelF, PlainVoxelArray)         \
    MACRO(VoxelSRgb, PlainVoxelArray)      \
    MACRO(VoxelFRgb, PlainVoxelArray)      \
    MACRO(VoxelSLabel, PlainVoxelArray)    \
    MACRO(VoxelSRgbLabel, PlainVoxelArray) \
    MACRO(VoxelS, VoxelBlockHash)          \
    MACRO(VoxelF, VoxelBlockHash)          \
    MACRO(VoxelSRgb, VoxelBlockHash)       \
    MACRO(VoxelFRgb, VoxelBlockHash)       \
    MACRO(VoxelSLabel, VoxelBlockHash)     \
    MACRO(VoxelSRgbLabel, VoxelBlockHash)
