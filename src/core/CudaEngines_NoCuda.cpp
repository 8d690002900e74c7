// The CUDA engine factories in a build without CUDA: asking for one is a clear error.

#include "voxfuse/core/Error.h"
#include "voxfuse/engines/IntegrationEngine.h"
#include "voxfuse/objects/Voxel.h"
#include "voxfuse/objects/VoxelBlockHash.h"

namespace voxfuse::cuda {

template <class TVoxel, class TIndex>
std::unique_ptr<IntegrationEngine<TVoxel, TIndex>> makeIntegrationEngine() {
    throw DeviceError("this VoxFuse build has no CUDA support (rebuild with -DVOXFUSE_CUDA=ON)");
}

template std::unique_ptr<IntegrationEngine<VoxelS, PlainVoxelArray>> makeIntegrationEngine<VoxelS, PlainVoxelArray>();
template std::unique_ptr<IntegrationEngine<VoxelF, PlainVoxelArray>> makeIntegrationEngine<VoxelF, PlainVoxelArray>();
template std::unique_ptr<IntegrationEngine<VoxelSRgb, PlainVoxelArray>> makeIntegrationEngine<VoxelSRgb, PlainVoxelArray>();
template std::unique_ptr<IntegrationEngine<VoxelFRgb, PlainVoxelArray>> makeIntegrationEngine<VoxelFRgb, PlainVoxelArray>();
template std::unique_ptr<IntegrationEngine<VoxelS, VoxelBlockHash>> makeIntegrationEngine<VoxelS, VoxelBlockHash>();
template std::unique_ptr<IntegrationEngine<VoxelF, VoxelBlockHash>> makeIntegrationEngine<VoxelF, VoxelBlockHash>();
template std::unique_ptr<IntegrationEngine<VoxelSRgb, VoxelBlockHash>> makeIntegrationEngine<VoxelSRgb, VoxelBlockHash>();
template std::unique_ptr<IntegrationEngine<VoxelFRgb, VoxelBlockHash>> makeIntegrationEngine<VoxelFRgb, VoxelBlockHash>();

}  // namespace voxfuse::cuda
