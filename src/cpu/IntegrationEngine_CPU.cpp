// CPU layer of the integration engine: src/engines/IntegrationEngine_Impl.h on the CPU launcher.

#include "core/CpuDevice.h"
#include "engines/IntegrationEngine_Impl.h"
#include "voxfuse/engines/EnginePairs.h"

namespace voxfuse::cpu {

template <class TVoxel, class TIndex>
std::unique_ptr<IntegrationEngine<TVoxel, TIndex>> makeIntegrationEngine() {
    return makeIntegrationEngineOn<CpuDevice, TVoxel, TIndex>();
}

#define VF_INSTANTIATE(TVoxel, TIndex) \
    template std::unique_ptr<IntegrationEngine<TVoxel, TIndex>> makeIntegrationEngine<TVoxel, TIndex>();
VF_FOR_EACH_ENGINE_PAIR(VF_INSTANTIATE)
#undef VF_INSTANTIATE

}  // namespace voxfuse::cpu
