#pragma once
// The voxel/index pairs every engine is built for, and the engines that have a CUDA layer, in one
// place. A device layer instantiates its factory for all pairs with
//   #define VF_INSTANTIATE(TVoxel, TIndex) template std::unique_ptr<Engine<TVoxel, TIndex>> makeEngine<TVoxel,
//   TIndex>(); VF_FOR_EACH_ENGINE_PAIR(VF_INSTANTIATE)
// so that adding a voxel or index type is one line here; a build without CUDA gets a stub that throws
// DeviceError for each engine of VF_FOR_EACH_CUDA_ENGINE (src/core/CudaEngines_NoCuda.cpp).

#include "voxfuse/objects/PlainVoxelArray.h"
#include "voxfuse/objects/Voxel.h"
#include "voxfuse/objects/VoxelBlockHash.h"

#define VF_FOR_EACH_ENGINE_PAIR(MACRO) VF_FOR_EACH_ENGINE_PAIR_WITH(VF_APPLY_ENGINE_PAIR, MACRO)

// The list itself: MACRO(ARG, TVoxel, TIndex) for every pair.
#define VF_FOR_EACH_ENGINE_PAIR_WITH(MACRO, ARG) \
    MACRO(ARG, VoxelS, PlainVoxelArray)          \
    MACRO(ARG, VoxelF, PlainVoxelArray)          \
    MACRO(ARG, VoxelSRgb, PlainVoxelArray)       \
    MACRO(ARG, VoxelFRgb, PlainVoxelArray)       \
    MACRO(ARG, VoxelSLabel, PlainVoxelArray)     \
    MACRO(ARG, VoxelSRgbLabel, PlainVoxelArray)  \
    MACRO(ARG, VoxelS, VoxelBlockHash)           \
    MACRO(ARG, VoxelF, VoxelBlockHash)           \
    MACRO(ARG, VoxelSRgb, VoxelBlockHash)        \
    MACRO(ARG, VoxelFRgb, VoxelBlockHash)        \
    MACRO(ARG, VoxelSLabel, VoxelBlockHash)      \
    MACRO(ARG, VoxelSRgbLabel, VoxelBlockHash)
#define VF_APPLY_ENGINE_PAIR(MACRO, TVoxel, TIndex) MACRO(TVoxel, TIndex)

// The voxel types, for the engines of the voxel block hash alone (swapping).
#define VF_FOR_EACH_VOXEL(MACRO) \
    MACRO(VoxelS)                \
    MACRO(VoxelF)                \
    MACRO(VoxelSRgb)             \
    MACRO(VoxelFRgb)             \
    MACRO(VoxelSLabel)           \
    MACRO(VoxelSRgbLabel)

// The templated engines with a CUDA layer (cuda/<Engine>_CUDA.cu), as their factory names them:
// make<Engine>() in namespace voxfuse::cuda.
#define VF_FOR_EACH_CUDA_ENGINE(MACRO) \
    MACRO(AllocationEngine)            \
    MACRO(IntegrationEngine)           \
    MACRO(RaycastEngine)               \
    MACRO(MeshingEngine)
