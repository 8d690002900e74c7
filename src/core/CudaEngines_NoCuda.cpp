// The CUDA engine factories in a build without CUDA: asking for one is a clear error.

#include "voxfuse/core/Error.h"
#include "voxfuse/engines/IntegrationEngine.h"
#include "voxfuse/engines/EnginePairs.h"
#include "voxfuse/objects/Voxel.h"
#include "voxfuse/objects/VoxelBlockHash.h"

namespace voxfuse::cuda {

template <class TVoxel, class TIndex>
std::unique_ptr<IntegrationEngine<TVoxel, TIndex>> makeIntegrationEngine() {
    throw DeviceError("this VoxFuse build has no CUDA support (rebuild with -DVOXFUSE_CUDA=ON)");
}

#define VF_INSTANTIATE(TVoxel, TIndex) template std::unique_ptr<IntegrationEngine<TVoxel, TIndex>> makeIntegrationEngine<TVoxel, TIndex>();
VF_FOR_EACH_ENGINE_PAIR(VF_INSTANTIATE)
#undef VF_INSTANTIATE

}  // namespace voxfuse::cuda
