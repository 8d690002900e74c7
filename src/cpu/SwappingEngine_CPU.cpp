// CPU layer of the swapping engine: src/engines/SwappingEngine_Impl.h on the CPU launcher.

#include "core/CpuDevice.h"
#include "engines/SwappingEngine_Impl.h"
#include "voxfuse/engines/EnginePairs.h"

namespace voxfuse::cpu {

template <class TVoxel>
std::unique_ptr<SwappingEngine<TVoxel>> makeSwappingEngine() {
    return makeSwappingEngineOn<CpuDevice, TVoxel>();
}

#define VF_INSTANTIATE(TVoxel) template std::unique_ptr<SwappingEngine<TVoxel>> makeSwappingEngine<TVoxel>();
VF_FOR_EACH_VOXEL(VF_INSTANTIATE)
#undef VF_INSTANTIATE

}  // namespace voxfuse::cpu
