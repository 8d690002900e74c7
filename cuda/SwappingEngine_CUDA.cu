// CUDA layer of the swapping engine: src/engines/SwappingEngine_Impl.h on the CUDA launcher.

#include "core/CudaDevice.cuh"
#include "engines/SwappingEngine_Impl.h"
#include "voxfuse/engines/EnginePairs.h"

namespace voxfuse::cuda {

template <class TVoxel>
std::unique_ptr<SwappingEngine<TVoxel>> makeSwappingEngine() {
    return makeSwappingEngineOn<CudaDevice, TVoxel>();
}

#define VF_INSTANTIATE(TVoxel) template std::unique_ptr<SwappingEngine<TVoxel>> makeSwappingEngine<TVoxel>();
VF_FOR_EACH_VOXEL(VF_INSTANTIATE)
#undef VF_INSTANTIATE

}  // namespace voxfuse::cuda
