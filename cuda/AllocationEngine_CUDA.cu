// CUDA layer of the allocation engine: the stages of src/engines/AllocationEngine_Impl.h on the
// CUDA launcher and primitives (kernels and CUB).

#include "core/CudaDevice.cuh"
#include "engines/AllocationEngine_Impl.h"
#include "voxfuse/engines/EnginePairs.h"

namespace voxfuse::cuda {

template <class TVoxel, class TIndex>
std::unique_ptr<AllocationEngine<TVoxel, TIndex>> makeAllocationEngine() {
    return makeAllocationEngineOn<CudaDevice, TVoxel, TIndex>();
}

#define VF_INSTANTIATE(TVoxel, TIndex) \
    template std::unique_ptr<AllocationEngine<TVoxel, TIndex>> makeAllocationEngine<TVoxel, TIndex>();
VF_FOR_EACH_ENGINE_PAIR(VF_INSTANTIATE)
#undef VF_INSTANTIATE

}  // namespace voxfuse::cuda
