// CPU layer of the meshing engine: src/engines/MeshingEngine_Impl.h on the CPU launcher (a team
// is one thread, which meshes its block alone).

#include "core/CpuDevice.h"
#include "engines/MeshingEngine_Impl.h"
#include "voxfuse/engines/EnginePairs.h"

namespace voxfuse::cpu {

template <class TVoxel, class TIndex>
std::unique_ptr<MeshingEngine<TVoxel, TIndex>> makeMeshingEngine() {
    return makeMeshingEngineOn<CpuDevice, TVoxel, TIndex>();
}

#define VF_INSTANTIATE(TVoxel, TIndex) \
    template std::unique_ptr<MeshingEngine<TVoxel, TIndex>> makeMeshingEngine<TVoxel, TIndex>();
VF_FOR_EACH_ENGINE_PAIR(VF_INSTANTIATE)
#undef VF_INSTANTIATE

}  // namespace voxfuse::cpu
