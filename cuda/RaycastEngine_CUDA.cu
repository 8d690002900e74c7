// CUDA layer of the raycast engine: src/engines/RaycastEngine_Impl.h on the CUDA launcher.

#include "core/CudaDevice.cuh"
#include "engines/RaycastEngine_Impl.h"
#include "voxfuse/engines/EnginePairs.h"

namespace voxfuse::cuda {

template <class TVoxel, class TIndex>
std::unique_ptr<RaycastEngine<TVoxel, TIndex>> makeRaycastEngine() {
    return makeRaycastEngineOn<CudaDevice, TVoxel, TIndex>();
}

#define VF_INSTANTIATE(TVoxel, TIndex) \
    template std::unique_ptr<RaycastEngine<TVoxel, TIndex>> makeRaycastEngine<TVoxel, TIndex>();
VF_FOR_EACH_ENGINE_PAIR(VF_INSTANTIATE)
#undef VF_INSTANTIATE

}  // namespace voxfuse::cuda
