// CPU layer of the low-level engine: src/engines/LowLevelEngine_Impl.h on the CPU launcher.

#include "core/CpuDevice.h"
#include "engines/LowLevelEngine_Impl.h"

namespace voxfuse::cpu {

std::unique_ptr<LowLevelEngine> makeLowLevelEngine() { return std::make_unique<LowLevelEngineOn<CpuDevice>>(); }

}  // namespace voxfuse::cpu
