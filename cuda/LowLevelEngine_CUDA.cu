// CUDA layer of the low-level engine: src/engines/LowLevelEngine_Impl.h on the CUDA launcher.

#include "core/CudaDevice.cuh"
#include "engines/LowLevelEngine_Impl.h"

namespace voxfuse::cuda {

std::unique_ptr<LowLevelEngine> makeLowLevelEngine() { return std::make_unique<LowLevelEngineOn<CudaDevice>>(); }

}  // namespace voxfuse::cuda
