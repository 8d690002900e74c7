// CUDA layer of the meshing engine: src/engines/MeshingEngine_Impl.h on the CUDA launcher (a team is a
// thread block of CudaDevice::kThreadsPerTeam threads, its block's neighbourhood in shared memory).

#include "core/CudaDevice.cuh"
#include "engines/MeshingEngine_Impl.h"
#include "voxfuse/engines/EnginePairs.h"

namespace voxfuse::cuda {

template <class TVoxel, class TIndex>
std::unique_ptr<MeshingEngine<TVoxel, TIndex>> makeMeshingEngine() {
    return makeMeshingEngineOn<CudaDevice, TVoxel, TIndex>();
}

#define VF_INSTANTIATE(TVoxel, TIndex) \
    template std::unique_ptr<MeshingEngine<TVoxel, TIndex>> makeMeshingEngine<TVoxel, TIndex>();
VF_FOR_EACH_ENGINE_PAIR(VF_INSTANTIATE)
#undef VF_INSTANTIATE

}  // namespace voxfuse::cuda
