// CPU layer of the trackers: src/engines/TrackerKernels_Impl.h on the CPU launcher.

#include "core/CpuDevice.h"
#include "engines/TrackerKernels_Impl.h"

namespace voxfuse::cpu {

std::unique_ptr<DepthTrackerKernels> makeDepthTrackerKernels() {
    return std::make_unique<DepthTrackerKernelsOn<CpuDevice>>();
}
std::unique_ptr<ColorTrackerKernels> makeColorTrackerKernels() {
    return std::make_unique<ColorTrackerKernelsOn<CpuDevice>>();
}

}  // namespace voxfuse::cpu
